"""Reinforcement-learning tasks and the PPO training script."""
