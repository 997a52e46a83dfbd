"""Decode PNG bytes with MuJoCo's own decoder (the one that loads the textures in a scene).

Example:
    >>> pixels = read_png(open("coco_000.png", "rb").read())  # (H, W, 3) uint8  # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np


def read_png(data: bytes) -> np.ndarray:
    """The pixels of a PNG as ``(H, W, C)`` uint8, decoded the way MuJoCo loads textures.

    Raises:
        ValueError: MuJoCo cannot decode the bytes.
    """
    import mujoco

    spec = mujoco.MjSpec()
    spec.assets = {"image.png": bytes(data)}
    spec.add_texture(name="image", type=mujoco.mjtTexture.mjTEXTURE_2D, file="image.png")
    model = spec.compile()
    shape = (int(model.tex_height[0]), int(model.tex_width[0]), int(model.tex_nchannel[0]))
    return np.array(model.tex_data[: int(np.prod(shape))]).reshape(shape)
