"""Datasets as specs (``rik dataset plan/build/list/show/verify``): a spec (:mod:`rik.schemas.dataset`) is expanded
into units of work with deterministic keys (:mod:`rik.dataset.plan`), which an engine runs on local processes or
a Ray cluster (:mod:`rik.dataset.engines`); finished units leave markers, so a rerun does only what is missing
(:mod:`rik.dataset.build`). Built datasets are listed in a small local registry (:mod:`rik.dataset.registry`)."""
