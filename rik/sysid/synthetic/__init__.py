"""Synthetic measured data: the simulated drawer and door trials, with their hidden ground truth, that rik's demo
(``rik sysid simulate``) and the sysid tests use.

- :mod:`rik.sysid.synthetic.generate`: rik's generator (MuJoCo, the effect laws of rik's library);
- :mod:`rik.sysid.synthetic.foreign`: a foreign generator whose force laws are written independently of rik's;
- :mod:`rik.sysid.synthetic.draws`: the small helpers (joint type, random draws) both share.

This package imports none of them itself."""
