"""Model discovery from measured joint trajectories: what the simulation gets wrong, the cause, the extended joint
model and the gain on held-out data (``rik sysid``; docs/sysid.md).

- :mod:`rik.sysid.trials`: measured trials in (CSV, Parquet, a LeRobot v3.0 dataset), units declared in the column
  headers and converted to SI, every bad input refused with a one-line :class:`~rik.errors.RikError`;
- :mod:`rik.sysid.preprocess`: resampling, Savitzky–Golay derivatives, the force-to-position delay, masks, the
  samples in contact with an end stop;
- :mod:`rik.sysid.breakaway`: starts of motion from rest and the force that broke the front away; creeps;
- :mod:`rik.sysid.effects`: the effect library as regressors with physical readings;
- :mod:`rik.sysid.fit`: equation-error fits of the baseline and of each effect, scored on held-out trials;
- :mod:`rik.sysid.select`: selection by held-out gain, BIC and physical sign; indistinguishable pairs;
- :mod:`rik.sysid.discover`: the pipeline end to end, with MuJoCo re-simulation (:mod:`rik.sysid.resim`);
- :mod:`rik.sysid.report`: report.md, plots and summary.json; :mod:`rik.sysid.preset`: the fitted joint as a
  user-catalog preset;
- :mod:`rik.sysid.synthetic`: simulated measurements for the demo and the tests. :mod:`rik.sysid.synthetic.generate`:
  ground-truth data with a hidden effect (``rik sysid simulate`` and the tests); :mod:`rik.sysid.synthetic.foreign`:
  a second generator whose laws are written without rik's library;
- :mod:`rik.sysid.profile`, :mod:`rik.sysid.profile_fit`, :mod:`rik.sysid.profile_report`: quasi-static force
  profiles (force against position, no time axis: ``rik sysid fit --quasi-static``).

Heavy libraries (scipy, pyarrow, mujoco, matplotlib) are imported inside functions, never here."""
