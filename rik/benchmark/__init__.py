"""The paper's resistance benchmark (``rik bench``): randomised front-opening episodes of scripted strategies,
with success, progress and slip per handle type, strategy and preset (its Table 3)."""
