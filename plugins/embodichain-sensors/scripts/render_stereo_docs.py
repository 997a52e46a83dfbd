"""Render the docs images of the stereo camera: left, right, depth and mask PNGs.

With the W1 robot (embodichain-robots) and the asset pack (embodichain-assets)
installed, the scene is the seed tutorial's: W1 with the ``eye_in_head`` stereo
camera (960x540, fx 450, 6 cm baseline, parent ``eyes``) looking at the circle
table, the fork, the drawer, a paper cup and a soda can. Without them, an inline arm with a table and
cubes is used (and the script says so).

Usage (from the repository root):
    .venv/bin/python plugins/embodichain-sensors/scripts/render_stereo_docs.py [--out docs/images]
"""

from __future__ import annotations

import argparse
import struct
import sys
import zlib
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[3]
#: W1 pose of the images: arms forward over the table, head pitched down.
READY = {
    "LEFT_J2": -0.7854,
    "LEFT_J4": -1.5708,
    "LEFT_J5": -0.7854,
    "RIGHT_J2": 0.7854,
    "RIGHT_J4": 1.5708,
    "RIGHT_J5": 0.7854,
    "NECK2": -0.5,
}
#: Objects added to the seed scene in front of the drawer: (uid, data path, position).
EXTRA_OBJECTS = (
    ("cup", "PaperCup/paper_cup.ply", (0.72, 0.3, 0.9), (0.2, 0.45, 0.85, 1.0)),
    ("can", "SodaCan/simple_cola_can.obj", (0.72, -0.3, 0.9), (0.8, 0.1, 0.1, 1.0)),
)


def eye_in_head(**overrides: Any) -> Any:
    """The seed tutorial's stereo camera config."""
    from embodichain_sensors.cfg import StereoCameraCfg

    cfg = dict(
        uid="eye_in_head",
        width=960,
        height=540,
        enable_mask=True,
        enable_depth=True,
        left_to_right_pos=(0.06, 0, 0),
        intrinsics=(450, 450, 480, 270),
        intrinsics_right=(450, 450, 480, 270),
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes"),
    )
    cfg.update(overrides)
    return StereoCameraCfg(**cfg)


def w1_scene() -> tuple[Any, Any]:
    """The seed scene with W1 and ``eye_in_head`` (needs embodichain-robots and -assets)."""
    from embodichain_assets.seed_scene import seed_scene_cfgs
    from embodichain_core.sim.cfg import RigidObjectCfg, RobotCfg, SimulationManagerCfg
    from embodichain_core.sim.data import get_data_path
    from embodichain_core.sim.scene import Scene
    from embodichain_core.sim.shapes import MeshCfg, VisualMaterialCfg
    from embodichain_sensors.stereo import StereoCamera

    cfgs = seed_scene_cfgs()
    scene = Scene(SimulationManagerCfg(), num_envs=1)
    scene.add_robot(
        RobotCfg.from_dict(
            {
                "robot_type": "DexforceW1",
                "uid": "dexforce_w1",
                "arm_kind": "anthropomorphic",
                "init_pos": [0.0, 0.0, 0.0],
            }
        )
    )
    scene.add_rigid_object(cfgs["table"], background=True)
    scene.add_rigid_object(cfgs["fork"])
    scene.add_articulation(cfgs["drawer"])
    scene.add_light(cfgs["light"])
    for uid, path, pos, rgba in EXTRA_OBJECTS:  # two more objects, so the mask shows more ids
        shape = MeshCfg(fpath=get_data_path(path), visual_material=VisualMaterialCfg(base_color=rgba))
        scene.add_rigid_object(RigidObjectCfg(uid=uid, shape=shape, init_pos=pos))
    camera = StereoCamera(eye_in_head(), scene)
    scene.add_sensor(camera)
    scene.build()
    robot = scene["dexforce_w1"]
    qpos = robot.get_qpos().clone()
    for name, value in READY.items():
        qpos[:, robot.joint_names.index(name)] = value
    robot.set_qpos(qpos, target=False)
    robot.set_qpos(qpos, target=True)
    return scene, camera


def fallback_scene() -> tuple[Any, Any]:
    """An inline 3-joint arm with a head ``eyes`` body, a table and two cubes."""
    from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg, SimulationManagerCfg
    from embodichain_core.sim.scene import Scene
    from embodichain_core.sim.shapes import CubeCfg
    from embodichain_sensors.stereo import StereoCamera

    head = (
        '<mujoco><worldbody><body name="base"><geom type="cylinder" size="0.1 0.6" pos="0 0 0.6"/>'
        '<body name="eyes" pos="0.1 0 1.45" euler="0 75 90" ><geom type="box" size="0.05 0.02 0.02"/>'
        "</body></body></worldbody></mujoco>"
    )
    scene = Scene(SimulationManagerCfg(), num_envs=1)
    scene.add_robot(RobotCfg(uid="robot", mjcf=head))
    scene.add_light(LightCfg(uid="lamp", init_pos=(0.0, 0.0, 2.0), intensity=30.0))
    scene.add_rigid_object(
        RigidObjectCfg(
            uid="table", shape=CubeCfg(size=[0.8, 1.0, 0.8]), init_pos=(0.8, 0.0, 0.4), body_type="kinematic"
        ),
        background=True,
    )
    for i, y in enumerate((-0.15, 0.12)):
        scene.add_rigid_object(
            RigidObjectCfg(uid=f"cube{i}", shape=CubeCfg(size=[0.06, 0.06, 0.06]), init_pos=(0.65, y, 0.83))
        )
    camera = StereoCamera(eye_in_head(), scene)
    scene.add_sensor(camera)
    scene.build()
    return scene, camera


def depth_image(depth: np.ndarray, near: float, far: float) -> np.ndarray:
    """Depth (H, W) to RGB on inverse depth (detail up close): near is bright yellow, far
    dark blue (a viridis-like ramp)."""
    anchors = np.array([[253, 231, 37], [94, 201, 98], [33, 145, 140], [59, 82, 139], [68, 1, 84]], dtype=np.float64)
    inv = 1.0 / np.maximum(depth, 1e-6)
    t = np.clip((1.0 / near - inv) / max(1.0 / near - 1.0 / far, 1e-9), 0.0, 1.0) * (len(anchors) - 1)
    lo = np.floor(t).astype(int).clip(0, len(anchors) - 2)
    frac = (t - lo)[..., None]
    return (anchors[lo] * (1 - frac) + anchors[lo + 1] * frac).astype(np.uint8)


def mask_image(mask: np.ndarray) -> np.ndarray:
    """Entity ids (H, W) to distinct colours (a categorical palette); -1 (nothing) is black."""
    palette = np.array(
        [
            [78, 121, 167],
            [242, 142, 43],
            [225, 87, 89],
            [118, 183, 178],
            [89, 161, 79],
            [237, 201, 72],
            [176, 122, 161],
            [255, 157, 167],
            [156, 117, 95],
            [186, 176, 172],
        ],
        dtype=np.uint8,
    )
    out = palette[np.maximum(mask, 0) % len(palette)]
    out[mask < 0] = 0
    return out


def write_png(path: Path, rgb: np.ndarray) -> None:
    """Write an (H, W, 3) uint8 image as PNG (zlib only)."""
    h, w = rgb.shape[:2]
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    path.write_bytes(png)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(REPO / "docs" / "images"))
    parser.add_argument("--settle", type=int, default=100, help="physics steps before rendering")
    args = parser.parse_args(argv)
    try:
        scene, camera = w1_scene()
        which = "W1 seed scene"
    except Exception as err:  # W1 or the asset pack not installed
        print(f"W1 scene unavailable ({type(err).__name__}: {err}); rendering the inline fallback", file=sys.stderr)
        scene, camera = fallback_scene()
        which = "inline fallback scene"
    scene.sim.step(args.settle)
    data = camera.get_data()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    depth = data["depth"][0, ..., 0].numpy()
    valid = depth[depth < camera.cfg.far * 0.999]
    near, far = (float(valid.min()), float(np.percentile(valid, 98))) if valid.size else (0.0, 1.0)
    images = {
        "stereo_left": data["color"][0, ..., :3].numpy(),
        "stereo_right": data["color_right"][0, ..., :3].numpy(),
        "stereo_depth": depth_image(depth, near, far),
        "stereo_mask": mask_image(data["mask"][0, ..., 0].numpy()),
    }
    for stem, image in images.items():
        write_png(out / f"{stem}.png", image)
    ids = sorted(int(i) for i in np.unique(data["mask"][0].numpy()))
    print(
        f"{which}: wrote {', '.join(images)} to {out}; depth {near:.2f}-{far:.2f} m; "
        f"mask ids {[(i, camera.uid_of_mask_id(i)) for i in ids]}"
    )
    camera.close()


if __name__ == "__main__":
    main()
