"""Camera tensors on an accelerator (the warp renderer on a GPU gives CUDA tensors) reach the
recorder and the dataset readers through ``.cpu()``: a stand-in tensor that refuses
``.numpy()`` until moved by ``.cpu()``, as a CUDA tensor does, is converted correctly."""

from __future__ import annotations

import numpy as np
import torch

from embodichain_lerobot.features import Source, to_numpy
from embodichain_lerobot.packing import depth_metres, pack_depth
from embodichain_lerobot.preview import _to_hwc_uint8


class DeviceTensor(torch.Tensor):
    """A CPU tensor that behaves like one on an accelerator for ``.numpy()``."""

    def numpy(self, *args, **kwargs):  # type: ignore[override]
        raise TypeError("can't convert cuda:0 device type tensor to numpy. Use Tensor.cpu() first.")

    def cpu(self, *args, **kwargs):  # type: ignore[override]
        return self.as_subclass(torch.Tensor).cpu(*args, **kwargs)


def on_device(arr: np.ndarray) -> torch.Tensor:
    return torch.from_numpy(arr).as_subclass(DeviceTensor)


def test_the_stand_in_refuses_numpy_like_a_cuda_tensor():
    t = on_device(np.zeros(3, dtype=np.float32))
    try:
        t.numpy()
    except TypeError as err:
        assert "Tensor.cpu()" in str(err)
    else:
        raise AssertionError("the stand-in converted without .cpu()")


def test_recorded_streams_of_device_tensors():
    rng = np.random.default_rng(0)
    rgba = rng.integers(0, 256, size=(2, 6, 8, 4), dtype=np.uint8)
    image = Source("sensor/cam/color", "observation.images.cam", "image", "uint8", (6, 8, 3))
    assert np.array_equal(image.convert(on_device(rgba), 2), rgba[..., :3])
    depth = rng.uniform(0.1, 2.0, size=(2, 6, 8)).astype(np.float32)
    packed = Source("sensor/cam/depth", "observation.depth.cam", "depth", "uint8", (6, 8, 3))
    assert np.array_equal(packed.convert(on_device(depth), 2), pack_depth(depth))
    state = Source("robot/qpos", "observation.state", "numeric", "float32", (3,))
    q = rng.normal(size=(2, 3)).astype(np.float32)
    assert np.array_equal(state.convert(on_device(q), 2), q)
    assert np.array_equal(to_numpy(on_device(q)), q)


def test_dataset_readers_take_device_tensors():
    depth = np.array([[0.5, 1.25]], dtype=np.float32)
    packed = pack_depth(depth)
    assert np.allclose(depth_metres(on_device(packed)), depth, atol=1e-3)
    chw = np.full((3, 2, 2), 0.5, dtype=np.float32)
    assert _to_hwc_uint8(on_device(chw)).shape == (2, 2, 3)


def test_colour_frames_copied_off_a_gpu_are_not_copied_again():
    """A GPU's frames reach the host as a fresh copy: the RGB frame is a view of it. A CPU
    tensor (the camera's own buffer on the CPU) is still copied, so the recorded frame never
    aliases memory the next render overwrites."""
    from embodichain_lerobot.features import _rgb

    rgba = np.random.default_rng(0).integers(0, 256, size=(2, 6, 8, 4), dtype=np.uint8)
    assert np.shares_memory(_rgb(rgba, owned=True), rgba)
    assert not np.shares_memory(_rgb(rgba), rgba)
    image = Source("sensor/cam/color", "observation.images.cam", "image", "uint8", (6, 8, 3))
    frame = torch.from_numpy(rgba)
    assert not np.shares_memory(image.convert(frame, 2), rgba)
    assert np.array_equal(image.convert(frame, 2), rgba[..., :3])
