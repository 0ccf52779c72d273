"""rik's contract with LeRobot: the feature keys and layouts of its datasets (:mod:`rik.lerobot.features`), one
frozen :class:`~rik.lerobot.policy_io.PolicyIO` that says what a policy reads and writes and travels from the export
to the policy folder to evaluation, what a policy folder may hold (:mod:`rik.lerobot.policy_files`), the
``--env.type=rik`` config LeRobot's tools read (:mod:`rik.lerobot.env_config`) and the hook that copies the contract
beside each checkpoint of ``lerobot-train`` (:mod:`rik.lerobot.train_hook`)."""
