"""Tutorial envs (the seed tutorials, runnable as scripts)."""
