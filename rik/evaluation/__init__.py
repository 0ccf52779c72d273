"""Policies on rik's benchmark: what a saved LeRobot policy reads, and running it (or a scripted strategy) on the
episodes of a catalog split, as the paper's Table 3 (``rik eval``)."""
