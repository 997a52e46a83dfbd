"""Env configs: ``EnvCfg`` (timing, batch, limits) and ``EmbodiedEnvCfg`` (the scene
and its managers), with every field settable from a JSON/YAML gym config."""

from __future__ import annotations

from typing import Any, Dict, List, Optional

from embodichain_core.sim.cfg import (
    ArticulationCfg,
    LightCfg,
    RigidObjectCfg,
    RigidObjectGroupCfg,
    RobotCfg,
    SensorCfg,
    SimulationManagerCfg,
)
from embodichain_core.utils.configclass import MISSING, configclass


@configclass
class EnvCfg:
    """Base env config.

    Attributes:
        num_envs: parallel environments (each its own MuJoCo simulation).
        sim_cfg: simulation settings (``physics_dt``, substeps, rendering).
        seed: RNG seed; ``None`` draws one (written back here); same seed, same rollout.
        sim_steps_per_control: physics steps per ``env.step``.
        target_control_frequency: if set, resolves ``sim_steps_per_control`` exactly
            from ``physics_dt`` (an inexact frequency is an error).
        ignore_terminations: only the time limit ends episodes.
        max_episode_steps: episode limit, kept inside the env; ``<= 0`` is unlimited.
        verbose: print the construction summary.
    """

    num_envs: int = 1
    sim_cfg: SimulationManagerCfg = SimulationManagerCfg()
    seed: Optional[int] = None
    sim_steps_per_control: int = 4
    target_control_frequency: Optional[float] = None
    ignore_terminations: bool = False
    max_episode_steps: int = 300
    verbose: bool = True


@configclass
class EmbodiedEnvCfg(EnvCfg):
    """The whole scene and its behaviour (see docs/embodied_env.md).

    ``articulation_cfg`` is accepted as an alias of ``articulation`` (the seed
    tutorial uses that name). ``custom_event_modes`` declares the event modes
    besides ``startup``/``reset``/``interval`` that task code applies
    (``env.event_manager.apply("attach", ids)``); an undeclared mode close to a
    known one (``"rset"``) is an error.
    """

    @configclass
    class EnvLightCfg:
        """``direct``: point/spot/directional lights; ``indirect``: ambient settings
        (``{"ambient": [r, g, b]}``)."""

        direct: List[LightCfg] = []
        indirect: Optional[Dict[str, Any]] = None

    robot: RobotCfg = MISSING
    control_parts: Optional[List[str]] = None
    active_joint_ids: List[int] = []
    sensor: List[SensorCfg] = []
    light: EnvLightCfg = EnvLightCfg()
    background: List[RigidObjectCfg] = []
    rigid_object: List[RigidObjectCfg] = []
    rigid_object_group: List[RigidObjectGroupCfg] = []
    articulation: List[ArticulationCfg] = []
    articulation_cfg: List[ArticulationCfg] = []
    events: Optional[Any] = None
    observations: Optional[Any] = None
    rewards: Optional[Any] = None
    actions: Optional[Any] = None
    dataset: Optional[Any] = None
    extensions: Optional[Dict[str, Any]] = None
    custom_event_modes: List[str] = []
    filter_visual_rand: bool = False
    filter_dataset_saving: bool = False
    init_rollout_buffer: bool = False
    #: An action outside the action space raises (``ValueError``) instead of being clipped
    #: by the action terms and drives (and counted; docs/embodied_env.md, "Actions").
    strict_actions: bool = False

    def validate(self, prefix: str = "", *, memory: bool = True, functors: bool = True) -> List[str]:
        """Check the config before the env builds anything.

        With a ``prefix`` (as the gym-config loader calls it) only the still-missing
        required fields are listed. Without one, a missing field raises, then every
        value is checked (run settings, simulation, physical values of the scene,
        manager sections unless ``functors=False``, the memory estimate unless
        ``memory=False``); see :func:`embodichain_core.config.validate.validate_env_cfg`.

        Raises:
            ConfigError: a missing field or a bad value, at its config path.
        """
        missing = super().validate(prefix)
        if not prefix:
            from embodichain_core.config.validate import validate_env_cfg

            validate_env_cfg(self, memory=memory, functors=functors)
        return missing

    def all_articulations(self) -> List[ArticulationCfg]:
        """``articulation`` plus the ``articulation_cfg`` alias."""
        return list(self.articulation) + list(self.articulation_cfg)
