"""Lowering a load to the seabed: the reference descent and the checks of a landing run."""
