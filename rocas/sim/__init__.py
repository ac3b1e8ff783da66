"""The pybullet-free world: map compilation, dynamics, oracles and the batched engine."""
