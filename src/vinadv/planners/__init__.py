"""Planners: the VIN model, its training, the fast batched planning engine and the reference planner."""
