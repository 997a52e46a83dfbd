"""Env classes and configs: ``BaseEnv`` (a step written in overrides, no managers) and
``EmbodiedEnv`` (the configuration-driven env built on it)."""

from embodichain_core.envs.base_env import BaseEnv
from embodichain_core.envs.cfg import EmbodiedEnvCfg, EnvCfg
from embodichain_core.envs.embodied_env import EmbodiedEnv
from embodichain_core.envs.registration import register_env

__all__ = ["BaseEnv", "EnvCfg", "EmbodiedEnv", "EmbodiedEnvCfg", "register_env"]
