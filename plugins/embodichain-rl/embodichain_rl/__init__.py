"""embodichain-rl: rsl_rl and Stable-Baselines3 adapters for batched embodichain envs.

* :class:`~embodichain_rl.rsl_rl_env.RslRlVecEnv`: an ``rsl_rl.env.VecEnv`` (torch, TensorDict
  observations, ``time_outs`` in the extras).
* :class:`~embodichain_rl.sb3_env.Sb3VecEnv`: a ``stable_baselines3`` ``VecEnv`` (numpy, CPU,
  ``terminal_observation`` and ``TimeLimit.truncated`` per env).
* :class:`~embodichain_rl.single_env.SingleEnvView`: one env of the batch as a plain numpy
  ``gymnasium.Env`` (for ``check_env``).
* ``embodichain train-rl`` (:mod:`embodichain_rl.cli`).

The adapters import their library on first use: ``import embodichain_rl`` stays light.
"""

__all__ = ["RslRlVecEnv", "Sb3VecEnv", "SingleEnvView", "ObsFlattener"]


def __getattr__(name: str):  # noqa: ANN202 - module-level lazy import
    modules = {
        "RslRlVecEnv": "rsl_rl_env",
        "Sb3VecEnv": "sb3_env",
        "SingleEnvView": "single_env",
        "ObsFlattener": "flatten",
    }
    if name not in modules:
        raise AttributeError(f"module 'embodichain_rl' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f"embodichain_rl.{modules[name]}"), name)
