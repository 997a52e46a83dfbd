"""A raw ``mujoco.batch.Batch`` loop that does the same physics work as ``env_throughput``'s env.

``env_throughput``'s plain raw twin writes ``ctrl`` and steps: its cubes rest on the
table and its episodes never end. The env's manager load changes the physics itself:
pushed cubes slide and collide, a reset puts cubes and arm in new places, and every
state write needs a forward before the next step. All of that is work any hand-written
env of the same task pays, so ``ratio_matched`` (env against this twin) is what the
framework itself costs, and ``ratio`` (env against the resting twin) is the whole
price of the task as configured.

The twin is the least numpy code that does the same: the same staggered episode
counters and 100-step episodes, the same per-env interval counters restarting with
each episode (every ``interval`` steps a random horizontal velocity of up to
``max_speed`` m/s for each cube), at an episode's end the cubes at random poses on the
table and the arm joints at their defaults plus noise, and one ``Batch.forward`` of the
rows written before the next ``Batch.step``. Its random numbers come from its own
numpy generator: the same distributions, not the same draws.

Example:
    >>> twin = MatchedTwin(env.unwrapped, nthread=2, nstep=4, stagger=stagger, workload=WORKLOAD)
    >>> twin.step(action_as_float64_numpy)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import mujoco
import mujoco.batch as mjbatch
import numpy as np

_VEL = mujoco.mjtStage.mjSTAGE_VEL


@dataclass(frozen=True)
class Workload:
    """What ``env_throughput``'s events do, as numbers (kept equal to its config there)."""

    cube_uids: tuple[str, ...]
    arm_part: str
    episode_length: int
    push_interval: int
    max_speed: float
    xy_low: tuple[float, float]
    xy_high: tuple[float, float]
    cube_z: float
    arm_noise: float


class MatchedTwin:
    """The raw batch loop with ``workload``'s pushes and resets (see the module doc).

    Args:
        base: the unwrapped benchmark env (model, start state, entity addresses).
        nthread: ``Batch`` threads, as the env's backend uses.
        nstep: MuJoCo steps per env step.
        stagger: each env's step count in its first episode (as the env's).
        workload: the events' numbers.
        seed: the twin's own random stream.
    """

    def __init__(self, base: Any, nthread: int, nstep: int, stagger: np.ndarray, workload: Workload, seed: int = 0):
        n = base.num_envs
        self.w, self.nstep, self.n = workload, nstep, n
        self.batch = mjbatch.Batch(base.scene.model, n, nthread=nthread, persistent=True)
        self.batch.reset(None)
        self.start = np.array(base.sim.state, dtype=np.float64)
        self.batch.state[...] = self.start
        self.batch.forward(None, stage=_VEL)
        self.qpos, self.qvel, self.ctrl = (self.batch.bind(k) for k in ("qpos", "qvel", "ctrl"))
        robot = base.robot
        jids = robot.get_joint_ids(workload.arm_part)
        self.arm_cols = robot.pos_act[jids].numpy()
        self.arm_qpos = robot.qpos_adr[jids].numpy()
        self.arm_default = robot.default_qpos[jids].numpy().astype(np.float64)
        self.cubes = [(base.scene[u].qpos_adr, base.scene[u].dof_adr) for u in workload.cube_uids]
        self.elapsed = np.array(stagger, dtype=np.int64)
        self.pushes = np.zeros(n, dtype=np.int64)
        self.dirty = np.zeros(n, dtype=bool)
        self.rng = np.random.default_rng(seed)

    def step(self, action: np.ndarray) -> None:
        """One env step: command, forward of the written rows, physics, pushes, resets."""
        self.ctrl[:, self.arm_cols] = action
        if self.dirty.any():
            self.batch.forward(np.flatnonzero(self.dirty), stage=_VEL)
            self.dirty[:] = False
        self.batch.step(nstep=self.nstep, stage=_VEL)
        self.pushes += 1
        due = np.flatnonzero(self.pushes % self.w.push_interval == 0)
        if len(due):
            self._push(due)
        self.elapsed += 1
        done = np.flatnonzero(self.elapsed >= self.w.episode_length)
        if len(done):
            self._reset(done)

    def _push(self, rows: np.ndarray) -> None:
        speed = self.w.max_speed
        for _, dof in self.cubes:
            self.qvel[rows, dof : dof + 6] = 0.0
            self.qvel[rows, dof : dof + 2] = self.rng.uniform(-speed, speed, (len(rows), 2))
        self.dirty[rows] = True

    def _reset(self, rows: np.ndarray) -> None:
        w, k = self.w, len(rows)
        self.batch.state[rows] = self.start[rows]
        for adr, _ in self.cubes:
            self.qpos[rows, adr : adr + 2] = self.rng.uniform(w.xy_low, w.xy_high, (k, 2))
            self.qpos[rows, adr + 2] = w.cube_z
            half_yaw = self.rng.uniform(-math.pi, math.pi, k) / 2
            self.qpos[rows, adr + 3 : adr + 7] = 0.0
            self.qpos[rows, adr + 3] = np.cos(half_yaw)
            self.qpos[rows, adr + 6] = np.sin(half_yaw)
        noise = self.rng.uniform(-w.arm_noise, w.arm_noise, (k, len(self.arm_qpos)))
        self.qpos[rows[:, None], self.arm_qpos[None, :]] = self.arm_default + noise
        self.elapsed[rows] = 0
        self.pushes[rows] = 0
        self.dirty[rows] = True
