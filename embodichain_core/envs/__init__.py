"""Env classes and configs (``BaseEnv`` is an alias of ``EmbodiedEnv``)."""

from embodichain_core.envs.base_env import BaseEnv
from embodichain_core.envs.cfg import EmbodiedEnvCfg, EnvCfg
from embodichain_core.envs.embodied_env import EmbodiedEnv
from embodichain_core.envs.registration import register_env

__all__ = ["BaseEnv", "EnvCfg", "EmbodiedEnv", "EmbodiedEnvCfg", "register_env"]
