"""Implementation modules of :mod:`embodichain_functors.observations` (import from there)."""
