"""Sensor model: radiance → electrons → noise → DN (pure functions, explicit rng)."""
