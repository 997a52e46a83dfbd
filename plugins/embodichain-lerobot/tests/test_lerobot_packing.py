"""Depth (millimetres) and masks (id + 1) packed losslessly as 16-bit values into RGB PNGs."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from embodichain_lerobot.packing import (
    DEPTH_MAX_MM,
    depth_metres,
    depth_millimetres,
    mask_ids,
    pack_depth,
    pack_mask,
    pack_u16,
    unpack_u16,
)


def _through_png(packed: np.ndarray) -> np.ndarray:
    """What ``LeRobotDataset`` returns for a stored image: float ``(3, H, W)`` in [0, 1]."""
    buf = io.BytesIO()
    Image.fromarray(packed).save(buf, format="PNG")
    return np.asarray(Image.open(buf)).transpose(2, 0, 1).astype(np.float32) / 255.0


def test_every_16_bit_value_survives_a_png_and_lerobots_float_conversion() -> None:
    values = np.arange(65536, dtype=np.uint16).reshape(256, 256)
    packed = pack_u16(values)
    assert packed.dtype == np.uint8 and packed.shape == (256, 256, 3)  # noqa: PT018
    np.testing.assert_array_equal(unpack_u16(packed), values)  # uint8 pixels
    np.testing.assert_array_equal(unpack_u16(_through_png(packed)), values)  # float (3, H, W) item


def test_depth_is_stored_in_millimetres_and_clipped() -> None:
    metres = [0.0, 1.2344, 1.2346, 70.0, np.inf, np.nan, -1.0]
    for depth in (np.array(metres, np.float32).reshape(1, 1, 7), np.array(metres, np.float32).reshape(1, 1, 7, 1)):
        item = _through_png(pack_depth(depth)[0])  # a camera's (N, H, W), a stereo camera's (N, H, W, 1)
        np.testing.assert_array_equal(depth_millimetres(item)[0], [0, 1234, 1235, DEPTH_MAX_MM, DEPTH_MAX_MM, 0, 0])
        np.testing.assert_allclose(depth_metres(item)[0, 1], 1.234, atol=1e-7)


def test_masks_store_id_plus_one_and_reject_ids_beyond_16_bits() -> None:
    mask = np.array([[[-1, 0, 7, 65534]]], dtype=np.int32)  # (N, H, W)
    np.testing.assert_array_equal(pack_mask(mask)[0, ..., 1], [[0, 1, 8, 255]])
    np.testing.assert_array_equal(pack_mask(mask[..., None]), pack_mask(mask))  # (N, H, W, 1)
    np.testing.assert_array_equal(mask_ids(_through_png(pack_mask(mask)[0])), mask[0])
    with pytest.raises(ValueError, match=r"mask ids must be in -1\.\.65534 .*got -1\.\.65535"):
        pack_mask(np.array([[-1, 65535]]))
