"""A recording with the browser viewer open is the same dataset as one without it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from viewer_helpers import action, demo_env, free_port, wait_for


def _record(root: Path, viewer: str) -> Path:
    env = demo_env(viewer, free_port(), dataset=root)
    try:
        env.reset(seed=3)
        for k in range(12):
            env.step(action(env, k))
            if k == 5:
                env.reset(options={"reset_ids": [1]})  # a short committed episode in env 1
        session = env.unwrapped._viewer
        if session is not None:  # the viewer really drew during the recording
            wait_for(lambda: session.viewer.frames > 1, "the viewer's frames")
        env.reset()  # commit the open episodes
    finally:
        env.close()
    (path,) = [p for p in root.iterdir() if p.is_dir()]
    return path


def _frames(path: Path) -> list[dict]:
    from embodichain_lerobot.reading import load_dataset

    ds = load_dataset(path)
    return [ds[i] for i in range(len(ds))]


@pytest.mark.usefixtures("every_step_published")
def test_dataset_with_the_viewer_equals_the_dataset_without(tmp_path: Path) -> None:
    without = _frames(_record(tmp_path / "off", "none"))
    with_viewer = _frames(_record(tmp_path / "on", "browser"))
    # env 0: one episode of 12 frames; env 1: two of 6 (reset after its 6th step)
    assert len(without) == len(with_viewer) == 24
    assert {int(f["episode_index"]) for f in with_viewer} == {0, 1, 2}
    for a, b in zip(without, with_viewer):
        assert a.keys() == b.keys()
        for key in a:
            va, vb = a[key], b[key]
            if hasattr(va, "numpy"):
                np.testing.assert_array_equal(va.numpy(), vb.numpy(), err_msg=key)
            else:
                assert va == vb, key
