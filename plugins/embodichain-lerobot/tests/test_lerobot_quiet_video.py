"""The mp4 writer of ``eval-policy --video`` and ``dataset preview --format mp4`` keeps FFmpeg's
encoder statistics off stderr, also after lerobot's video helpers restored FFmpeg's default log
callback (which prints x264's info-level lines), so ``--quiet`` output stays quiet."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

av = pytest.importorskip("av")


def test_write_mp4_prints_no_encoder_statistics(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    import av.logging

    from embodichain_lerobot.preview import write_mp4

    av.logging.restore_default_callback()  # what lerobot's encode/decode helpers leave behind
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (32, 48, 3), dtype=np.uint8) for _ in range(6)]
    path = write_mp4({"cam": frames}, 10, tmp_path / "out.mp4")
    assert path.stat().st_size > 0
    err = capfd.readouterr().err
    assert "libx264" not in err
    assert "frame I:" not in err
