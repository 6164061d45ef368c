"""Studies and benchmarks (nothing in the core imports them)."""
