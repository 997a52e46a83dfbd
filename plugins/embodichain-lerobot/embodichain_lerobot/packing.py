"""Depth and mask maps as lossless 16-bit values in RGB PNG image features.

lerobot's image features are 3-channel uint8 PNGs, so a 16-bit value ``v`` is
stored as ``R = v >> 8``, ``G = v & 255``, ``B = 0`` (PNG is lossless, so the
value comes back exactly):

* ``observation.depth.<cam>``: z-depth in **millimetres** (``round(metres * 1000)``),
  clipped to 0..65535; 65535 means "65.535 m or farther" (no surface within range);
* ``observation.mask.<cam>``: entity id + 1 (0: no entity; the sensor's ``-1``).

``LeRobotDataset`` returns these features like any image, as float ``(3, H, W)``
in [0, 1]; :func:`depth_millimetres`, :func:`depth_metres` and :func:`mask_ids` turn such an item (or the
uint8 ``(H, W, 3)`` PNG pixels) back into metres and ids.

Example:
    >>> import numpy as np
    >>> packed = pack_u16(np.array([[[1234]]], dtype=np.uint16))
    >>> int(unpack_u16(packed)[0, 0, 0])
    1234
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Depth unit of the stored maps: millimetres per metre.
DEPTH_SCALE = 1000.0
#: The largest stored depth (millimetres); also "nothing within range".
DEPTH_MAX_MM = 65535


def pack_u16(values: np.ndarray) -> np.ndarray:
    """``(..., H, W)`` uint16 values as ``(..., H, W, 3)`` uint8 RGB."""
    v = np.asarray(values, dtype=np.uint16)
    out = np.zeros(v.shape + (3,), dtype=np.uint8)
    out[..., 0] = v >> 8
    out[..., 1] = v & 0xFF
    return out


def _as_uint8_hwc(image: Any) -> np.ndarray:
    """An image item (float ``(..., 3, H, W)`` in [0, 1], a tensor, or uint8 ``(..., H, W, 3)``) as uint8 HWC."""
    arr = np.asarray(image.detach().cpu().numpy() if hasattr(image, "detach") else image)  # a tensor on any device
    if arr.dtype != np.uint8:
        arr = np.rint(np.clip(arr, 0.0, 1.0) * 255.0).astype(np.uint8)
        if arr.shape[-1] != 3 and arr.shape[-3] == 3:  # channels first, as LeRobotDataset returns
            arr = np.moveaxis(arr, -3, -1)
    return arr


def unpack_u16(image: Any) -> np.ndarray:
    """The uint16 values ``(..., H, W)`` of a packed image (see the module docstring)."""
    arr = _as_uint8_hwc(image)
    return (arr[..., 0].astype(np.uint16) << 8) | arr[..., 1].astype(np.uint16)


def _batch_maps(maps: np.ndarray) -> np.ndarray:
    """``(N, H, W)`` or ``(N, H, W, 1)`` (a stereo camera's trailing 1) as ``(N, H, W)``."""
    arr = np.asarray(maps)
    return arr[..., 0] if arr.ndim == 4 and arr.shape[-1] == 1 else arr


def pack_depth(depth_m: np.ndarray) -> np.ndarray:
    """Depth in metres (``(N, H, W[, 1])`` float) as packed millimetres ``(N, H, W, 3)`` uint8."""
    metres = np.nan_to_num(_batch_maps(depth_m).astype(np.float64), nan=0.0, posinf=DEPTH_MAX_MM)
    return pack_u16(np.clip(np.rint(metres * DEPTH_SCALE), 0, DEPTH_MAX_MM))


def pack_mask(mask: np.ndarray) -> np.ndarray:
    """Entity ids (``(N, H, W[, 1])`` int, -1 none) as packed ``id + 1`` ``(N, H, W, 3)`` uint8.

    Raises:
        ValueError: an id outside -1..65534.
    """
    ids = _batch_maps(mask).astype(np.int64) + 1
    if ids.size and (ids.min() < 0 or ids.max() > 0xFFFF):
        raise ValueError(
            f"mask ids must be in -1..65534 to be stored as 16-bit values, got "
            f"{int(ids.min()) - 1}..{int(ids.max()) - 1}"
        )
    return pack_u16(ids)


def depth_millimetres(image: Any) -> np.ndarray:
    """A stored depth image as uint16 millimetres ``(..., H, W)`` (65535: nothing within range)."""
    return unpack_u16(image)


def depth_metres(image: Any) -> np.ndarray:
    """A stored depth image as float32 metres ``(..., H, W)`` (exact to the millimetre)."""
    return unpack_u16(image).astype(np.float32) / np.float32(DEPTH_SCALE)


def mask_ids(image: Any) -> np.ndarray:
    """A stored mask image as int32 entity ids ``(..., H, W)`` (-1: no entity)."""
    return unpack_u16(image).astype(np.int32) - 1
