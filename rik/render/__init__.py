"""Image streams of recorded episodes and the gap between them and real images.

- :mod:`rik.render.streams`, :mod:`rik.render.episodes`: resumable per-episode streams (``rik render``,
  ``rik rerender``), replayed from the exact recorded states;
- :mod:`rik.render.renderers`: MuJoCo's rasteriser (the ``sim`` stream) and the Mitsuba 3 path tracer (the
  ``rerendered`` stream), built on :mod:`rik.render.mitsuba_scene`, :mod:`rik.render.materials` and
  :mod:`rik.render.backend` (which Mitsuba variant);
- :mod:`rik.render.align`: the silhouette check that both streams show the same geometry;
- :mod:`rik.render.visual_gap`, :mod:`rik.render.metrics`, :mod:`rik.render.encoders`: FID, KID and EMD over
  ResNet and CLIP features (``rik visual-gap``).

Heavy libraries (mujoco, mitsuba, torch) are imported inside functions, never here."""
