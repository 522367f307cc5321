"""The synthetic floor world: what the two rigs see as the robot drives, with ground truth."""
