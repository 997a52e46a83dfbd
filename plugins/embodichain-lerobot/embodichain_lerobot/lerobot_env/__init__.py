"""lerobot's own commands on embodichain tasks: ``--env.type=embodichain``.

Importing this package (``--env.discover_packages_path=embodichain_lerobot.lerobot_env``)
registers :class:`~embodichain_lerobot.lerobot_env.config.EmbodiChainEnv` as lerobot's env
type ``embodichain`` and the gym id its factory builds.

Example:
    $ lerobot-eval --env.discover_packages_path=embodichain_lerobot.lerobot_env \\
          --env.type=embodichain --env.task=PickFork-v1 \\
          --policy.path=outputs/act/checkpoints/last/pretrained_model \\
          --eval.n_episodes=10 --eval.batch_size=2
"""

from __future__ import annotations

import gymnasium as gym

from embodichain_lerobot.lerobot_env.view import GYM_ID

if GYM_ID not in gym.registry:
    # the view is a plain single env: no order or env checker wrappers around it, so
    # lerobot's rollout reads its task_description and _max_episode_steps
    gym.register(GYM_ID, entry_point="embodichain_lerobot.lerobot_env.view:make_view", order_enforce=False)

from embodichain_lerobot.lerobot_env.config import ENV_TYPE, EmbodiChainEnv, EnvConfigError  # noqa: E402

__all__ = ["EmbodiChainEnv", "EnvConfigError", "ENV_TYPE", "GYM_ID"]
