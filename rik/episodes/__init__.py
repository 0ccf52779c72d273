"""Episodes: scripted strategies (:mod:`.operators`) run on a scene and recorded (:mod:`.record`), the episode
format on disk (:mod:`.episode`: meta.json and states.parquet), exact replay (:mod:`.replay`), and the seeded
draw of variants, presets and strategies that the benchmark, the gym env and ``rik eval`` share (:mod:`.draw`)."""
