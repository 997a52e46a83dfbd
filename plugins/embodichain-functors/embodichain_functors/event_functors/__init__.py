"""Implementation modules of :mod:`embodichain_functors.events` (import from there)."""
