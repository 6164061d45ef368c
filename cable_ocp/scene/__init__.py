"""Scenes: the validated scene files a run reads, the bundled ones, and results folders."""
