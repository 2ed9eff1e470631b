"""Lens optics: pure functions on arrays (no I/O, no OpenGL)."""
