"""embodichain-core: configuration-driven robot-learning environments on MuJoCo."""

__version__ = "0.1.0"
