"""Render each robot of embodichain-robots at its home pose to docs/images/.

Usage (from the repository root):
    .venv/bin/python plugins/embodichain-robots/scripts/render_robots.py [--out docs/images]

Offscreen MuJoCo rendering: EGL by default (Mesa works on CPU-only machines);
set ``MUJOCO_GL=osmesa`` where EGL is not available.
"""

from __future__ import annotations

import argparse
import os
import sys
import zlib
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[3]

#: The docs' mirror example: both hands in front of the chest, palms down.
READY = {
    "LEFT_J2": -0.7854,
    "LEFT_J4": -1.5708,
    "LEFT_J5": -0.7854,
    "RIGHT_J2": 0.7854,
    "RIGHT_J4": 1.5708,
    "RIGHT_J5": 0.7854,
    "NECK2": -0.3,
}
#: file stem -> (config dict, camera lookat, distance, azimuth, elevation, image size, qpos overrides)
SHOTS: dict[str, tuple] = {
    "robot_dexforce_w1": ({"robot_type": "DexforceW1", "uid": "w1"}, (0.0, 0.0, 0.95), 3.1, 145, -12, (720, 900), {}),
    "robot_dexforce_w1_ready": (
        {"robot_type": "DexforceW1", "uid": "w1"},
        (0.1, 0.0, 0.95),
        2.7,
        150,
        -14,
        (720, 900),
        READY,
    ),
    "robot_dexforce_w1_industrial": (
        {"robot_type": "DexforceW1", "uid": "w1", "arm_kind": "industrial"},
        (0.0, 0.0, 0.95),
        3.1,
        145,
        -12,
        (720, 900),
        {},
    ),
    "robot_seven_dof_arm": (
        {"robot_type": "SevenDofArm", "uid": "arm"},
        (0.18, 0.0, 0.38),
        1.25,
        135,
        -16,
        (800, 720),
        {},
    ),
}


def build_scene(cfg_dict: dict) -> Any:
    """A one-env scene with the robot and two lights."""
    from embodichain_core.sim.cfg import LightCfg, RobotCfg, SimulationManagerCfg
    from embodichain_core.sim.scene import Scene

    scene = Scene(SimulationManagerCfg(width=1024, height=1024), num_envs=1)
    scene.add_robot(RobotCfg.from_dict(cfg_dict))
    scene.add_light(LightCfg(uid="key", light_type="point", init_pos=(2.5, 1.5, 3.0), intensity=45))
    scene.add_light(LightCfg(uid="fill", light_type="point", init_pos=(-2.0, -2.0, 2.5), intensity=20))
    sky = scene.builder.spec.add_texture(name="render_sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX)
    sky.builtin = mujoco.mjtBuiltin.mjBUILTIN_GRADIENT
    sky.rgb1, sky.rgb2, sky.width, sky.height = [0.62, 0.70, 0.80], [0.16, 0.18, 0.22], 256, 1536
    scene.builder.spec.visual.headlight.diffuse = [0.45, 0.45, 0.45]
    scene.build()
    return scene


def render_shot(stem: str, out_dir: Path) -> Path:
    """Render one entry of :data:`SHOTS` and write ``<out_dir>/<stem>.png``."""
    cfg, lookat, distance, azimuth, elevation, (width, height), overrides = SHOTS[stem]
    scene = build_scene(cfg)
    robot = scene[cfg["uid"]]
    if overrides:
        qpos = robot.get_qpos().clone()
        for name, value in overrides.items():
            qpos[:, robot.joint_names.index(name)] = value
        robot.set_qpos(qpos, target=False)
    model, data = scene.sim.get_model(0), scene.sim.get_data(0)
    mujoco.mj_forward(model, data)
    camera = mujoco.MjvCamera()
    camera.lookat[:], camera.distance, camera.azimuth, camera.elevation = lookat, distance, azimuth, elevation
    with mujoco.Renderer(model, height=height, width=width) as renderer:
        renderer.update_scene(data, camera=camera)
        image = renderer.render()
    path = out_dir / f"{stem}.png"
    write_png(path, image)
    return path


def write_png(path: Path, rgb: np.ndarray) -> None:
    """Write an (H, W, 3) uint8 image as PNG with zlib only."""
    import struct

    height, width, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[row].tobytes() for row in range(height))

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "images")
    parser.add_argument("--only", nargs="*", choices=sorted(SHOTS), help="render only these images")
    args = parser.parse_args(argv)
    for stem in args.only or SHOTS:
        print(render_shot(stem, args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
