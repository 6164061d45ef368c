"""Runs of the model: statics, RK4 integration, trajectories, clearance."""
