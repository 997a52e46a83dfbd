"""The construction summary of an env: timing, scene and every manager (a ``BaseEnv``
has none: its summary ends with the scene)."""

from __future__ import annotations

from typing import Any


def summary_text(env: Any) -> str:
    """A box-drawn summary: runtime, timing, scene and managers with their functors."""
    lines = [f"╭─ Environment initialized: {type(env).__name__}"]
    add = lines.append
    add(f"│ Parallel environments  {env.num_envs}   device {env.device}   seed {env.cfg.seed}")
    add(f"│ Backend  {backend_text(env)}")
    add(
        f"│ Physics  {env.physics_dt:g} s ({env.physics_frequency:g} Hz, {env.cfg.sim_cfg.physics_substeps} MuJoCo substeps)"
    )
    add(f"│ Control  {env.step_dt:g} s ({env.control_frequency:g} Hz, {env.sim_steps_per_control} physics steps)")
    add(f"│ Episode limit  {env.cfg.max_episode_steps} steps")
    scene = env.scene
    robot = getattr(env, "robot", None)  # EmbodiedEnv's; a BaseEnv's robots are listed below
    if robot is not None:
        add(f"│ Robot  {robot.uid} ({robot.dof} joints, {len(env.active_joint_ids)} active)")
    for label, items in (
        ("Robots", {} if robot is not None else scene.robots),
        ("Sensors", scene.sensors),
        ("Lights", scene.lights),
        ("Rigid objects", scene.rigid_objects),
        ("Background", scene.backgrounds),
        ("Articulations", scene.articulations),
        ("Groups", scene.groups),
    ):
        if items:
            add(f"│ {label}  {', '.join(items)}")
    if hasattr(env, "event_manager"):
        _manager_lines(env, add)
    add("╰─ Ready")
    return "\n".join(lines)


def _manager_lines(env: Any, add: Any) -> None:
    managers = [
        ("Event", env.event_manager),
        ("Observation", env.observation_manager),
        ("Reward", env.reward_manager),
        ("Action", env.action_manager),
        ("Dataset", env.dataset_manager),
    ]
    active = [m for _, m in managers if m is not None and len(m)]
    add(f"│ Managers ({len(active)}/5 active, {sum(len(m) for m in active)} functors)")
    for label, manager in managers:
        if manager is None or not len(manager):
            add(f"│   {label}: disabled")
            continue
        add(f"│   {label}:")
        for mode, name, detail in manager.summary_rows():
            add(f"│     [{mode}] {name}: {detail}")


def backend_text(env: Any) -> str:
    """``mujoco_batch (CPU threads: 2, float64)`` or ``warp (MuJoCo Warp on cuda:0, float32)``."""
    sim_cfg = env.cfg.sim_cfg
    backend = getattr(sim_cfg, "backend", "mujoco_batch")
    if backend == "warp":
        return f"warp (MuJoCo Warp on {sim_cfg.sim_device}, float32)"
    threads = getattr(getattr(env, "sim", None), "nthread", None)
    return f"{backend} (CPU threads: {threads if threads is not None else 'auto'}, float64)"


def print_summary(env: Any) -> None:
    print(summary_text(env), flush=True)
