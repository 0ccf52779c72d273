"""Learned policies on rik: loading a saved LeRobot policy and evaluating it on rik's benchmark."""
