"""Small scenes for the sensor tests: a table, a cube, a light, optionally an arm."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from embodichain_core.plugins import get_sensor_classes
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.shapes import CubeCfg

#: A 2-joint arm with a head body ``eyes`` (camera mount) and a site ``tip``.
HEAD_ARM = """
<mujoco model="head_arm">
  <worldbody>
    <body name="base"><geom type="cylinder" size="0.05 0.02"/>
      <body name="link1" pos="0 0 0.04"><joint name="j1" axis="0 0 1" range="-3 3"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.03"/>
        <body name="eyes" pos="0.05 0 0.3" quat="0.70711 0 0.70711 0">
          <geom type="box" size="0.01 0.03 0.01"/>
          <site name="tip" pos="0 0 0.02"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

CUBE_POS = (0.35, -0.15, 0.05)
CUBE_SIZE = 0.1
TABLE_POS = (0.0, 0.8, 0.2)


def make_scene(
    *sensor_cfgs: Any,
    num_envs: int = 1,
    robot: bool = False,
    cube_dynamic: bool = False,
    sim_cfg: SimulationManagerCfg | None = None,
) -> tuple[Scene, list[Any]]:
    """A built scene with a cube (static unless ``cube_dynamic``), a kinematic
    table, a point light ``lamp`` and the sensors of ``sensor_cfgs``."""
    scene = Scene(sim_cfg or SimulationManagerCfg(), num_envs=num_envs)
    if robot:
        scene.add_robot(RobotCfg(uid="arm", mjcf=HEAD_ARM, control_parts={"all": ["j1"]}))
    scene.add_light(LightCfg(uid="lamp", init_pos=(0.0, 0.0, 2.0)))
    scene.add_rigid_object(
        RigidObjectCfg(uid="table", shape=CubeCfg(size=[0.4, 0.4, 0.4]), init_pos=TABLE_POS, body_type="kinematic"),
        background=True,
    )
    cube = RigidObjectCfg(
        uid="cube",
        shape=CubeCfg(size=[CUBE_SIZE] * 3),
        init_pos=CUBE_POS,
        body_type="dynamic" if cube_dynamic else "static",
    )
    scene.add_rigid_object(cube, background=not cube_dynamic)
    sensors = [add_sensor(scene, cfg) for cfg in sensor_cfgs]
    scene.build()
    return scene, sensors


def add_sensor(scene: Scene, cfg: Any) -> Any:
    """Construct the registered sensor of ``cfg`` and add it to ``scene``."""
    _, sensor_cls = get_sensor_classes(cfg.sensor_type)
    sensor = sensor_cls(cfg, scene)
    scene.add_sensor(sensor)
    return sensor


def project_opencv(
    point_world: Sequence[float], eye: Sequence[float], rot_world_cam: np.ndarray, intrinsics: Sequence[float]
) -> tuple[float, float, float]:
    """``(u, v, z)`` of a world point for an OpenGL camera frame, by the textbook formula."""
    fx, fy, cx, cy = intrinsics
    p = rot_world_cam.T @ (np.asarray(point_world, float) - np.asarray(eye, float))
    x, y, z = p[0], -p[1], -p[2]  # OpenGL -> OpenCV camera frame
    return fx * x / z + cx, fy * y / z + cy, z


def cube_corners(center: Sequence[float] = CUBE_POS, size: float = CUBE_SIZE) -> np.ndarray:
    h = size / 2
    return np.array(
        [
            [center[0] + sx * h, center[1] + sy * h, center[2] + sz * h]
            for sx in (-1, 1)
            for sy in (-1, 1)
            for sz in (-1, 1)
        ]
    )


def mask_bbox(mask: np.ndarray, value: int) -> tuple[int, int, int, int]:
    """``(u_min, u_max, v_min, v_max)`` of the pixels equal to ``value``."""
    vs, us = np.nonzero(mask == value)
    return int(us.min()), int(us.max()), int(vs.min()), int(vs.max())
