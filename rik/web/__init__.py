"""The web app (``rik serve``): catalog pages and the browser teleop station. Serving only: the simulation lives in
:mod:`rik.sim`, the catalog in :mod:`rik.registry` and :mod:`rik.assets`."""
