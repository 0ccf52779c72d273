"""The simulated scene: a built variant loaded with its robot (:mod:`.scene`), the gripper frame's maths
(:mod:`.pose`), what the scene shows a policy (:mod:`.observation`), how an attempt ended (:mod:`.outcome`) and
where a handle's hooks are (:mod:`.probe`); the robots live in :mod:`.robots`. Heavy libraries are imported
inside functions, never here."""
