"""Joint effects, in one place: the effects a furniture joint has beyond damping, Coulomb friction and a
linear spring (:data:`rik.schemas.joints.JointEffect`).

- :mod:`rik.joints.kinds`: the one table of effect kinds (schema class, how MuJoCo expresses each kind, how
  rik's simulator applies it otherwise); every list of kinds in rik derives from it;
- :mod:`rik.joints.laws`: the force laws (numpy, SI units of the joint);
- :mod:`rik.joints.mjcf`: the mapping of a joint's resistance and native effects to MJCF;
- :mod:`rik.joints.runtime`: the per-physics-step application of the effects MuJoCo lacks.

This package depends on :mod:`rik.schemas` and :mod:`rik.errors` only (never on :mod:`rik.sim`,
:mod:`rik.combinator` or :mod:`rik.sysid`, which use it); tests/test_layering.py holds it to that.
"""
