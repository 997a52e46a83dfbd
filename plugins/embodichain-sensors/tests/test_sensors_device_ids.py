"""Env ids on an accelerator (CUDA tensors on the warp backend) are moved with ``.cpu()``
before numpy indexing: a stand-in tensor that refuses ``.numpy()`` until moved works."""

from __future__ import annotations

import torch

from embodichain_sensors.cfg import CameraCfg, StereoCameraCfg

EYE = (0.35, -0.15, 1.2)


class DeviceTensor(torch.Tensor):
    """A CPU tensor that behaves like one on an accelerator for ``.numpy()``."""

    def numpy(self, *args, **kwargs):  # type: ignore[override]
        raise TypeError("can't convert cuda:0 device type tensor to numpy. Use Tensor.cpu() first.")

    def cpu(self, *args, **kwargs):  # type: ignore[override]
        return self.as_subclass(torch.Tensor).cpu(*args, **kwargs)


def ids(*values: int) -> torch.Tensor:
    return torch.tensor(values, dtype=torch.long).as_subclass(DeviceTensor)


def test_camera_pose_and_intrinsics_setters_take_device_env_ids(scene_factory):
    _, (cam,) = scene_factory(CameraCfg(uid="cam", width=32, height=24), num_envs=2)
    cam.set_local_pose(torch.tensor([[0.1, 0.2, 0.3, 1.0, 0.0, 0.0, 0.0]]), env_ids=ids(1))
    assert torch.allclose(cam.get_local_pose()[1, :3], torch.tensor([0.1, 0.2, 0.3]))
    cam.look_at(EYE, (0.35, -0.15, 0.0), up=(1.0, 0.0, 0.0), env_ids=ids(0))
    assert torch.allclose(cam.get_local_pose()[0, :3], torch.tensor(EYE))
    cam.set_intrinsics(torch.tensor([[50.0, 50.0, 16.0, 12.0]]), env_ids=ids(1))
    assert cam.get_intrinsics()[1, 0, 0] == 50.0


def test_stereo_intrinsics_take_device_env_ids(scene_factory):
    cfg = StereoCameraCfg(uid="stereo", width=32, height=24, left_to_right_pos=(0.06, 0.0, 0.0))
    _, (cam,) = scene_factory(cfg, num_envs=2)
    cam.set_intrinsics(torch.tensor([[40.0, 40.0, 16.0, 12.0]]), env_ids=ids(0))
    left, right = cam.get_intrinsics()
    assert left[0, 0, 0] == 40.0
    assert right[0, 0, 0] == 40.0
