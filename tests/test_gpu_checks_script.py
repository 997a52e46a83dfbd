"""``benchmarks/gpu_checks.sh`` runs every part with its arguments and keeps going when one
fails or hangs (a stand-in interpreter records the calls; the real parts need a CUDA GPU)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STAND_IN = """#!{python}
import json, sys, time
args = sys.argv[1:]
out = args[args.index("--out") + 1]
if "gpu_throughput.py" in args[0]:
    sys.exit(3)  # a part that fails
if "--case" in args and args[args.index("--case") + 1] == "camera":
    time.sleep(30)  # a part that hangs past its limit
json.dump(args, open(out, "w"))
print("ran", " ".join(args))
"""


def test_every_part_runs_and_a_failing_or_hung_part_leaves_the_others(tmp_path: Path) -> None:
    python = tmp_path / "python"
    python.write_text(STAND_IN.format(python=sys.executable))
    python.chmod(0o755)
    script = (ROOT / "benchmarks" / "gpu_checks.sh").read_text().replace("part camera 60 ", "part camera 2 ")
    (tmp_path / "gpu_checks.sh").write_text(script)
    out = tmp_path / "out"
    done = subprocess.run(
        ["bash", str(tmp_path / "gpu_checks.sh"), str(out), str(python)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ},
    )
    assert done.returncode == 0, done.stderr
    assert "== throughput: exit 3" in done.stdout
    assert "== camera: exit 124" in done.stdout  # timeout's code: the hung part was stopped
    for name in ("syncs", "main_job"):
        args = json.loads((out / f"{name}.json").read_text())
        assert args[0] == "benchmarks/gpu_main_job.py"
        assert args[args.index("--device") + 1] == "cuda"
    job = json.loads((out / "main_job.json").read_text())
    assert job[job.index("--num-envs") + 1 : job.index("--out")] == ["64", "256", "1024"]
    assert not (out / "throughput.json").exists()
    assert sorted(p.name for p in out.glob("*.log")) == ["camera.log", "main_job.log", "syncs.log", "throughput.log"]
