"""Helpers of the benchmark smoke tests (a uniquely named module: test dirs share sys.path).

The smoke tests run a script of ``benchmarks/`` in a subprocess of this interpreter, from the
checkout's root, and read the JSON it writes; a few import a benchmark module to test its
parts. No timing is ever asserted (the box is shared and noisy).

Example:
    >>> proc, data = run_benchmark("cold_ops.py", "--rounds", "3", out=tmp_path / "cold.json")  # doctest: +SKIP
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

#: The checkout's root (the benchmarks run from there).
ROOT = Path(__file__).resolve().parents[1]
#: Its ``benchmarks/`` folder.
BENCHMARKS = ROOT / "benchmarks"
#: How much of a failed run's stdout and stderr (each) an assertion message shows.
OUTPUT_TAIL = 3000


def run_script(script: str, *args: str, timeout: float = 280) -> subprocess.CompletedProcess:
    """Run ``benchmarks/<script>`` with ``args`` and return the finished process (its stdout
    and stderr captured as text), whatever its exit code."""
    return subprocess.run(
        [sys.executable, str(BENCHMARKS / script), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def run_benchmark(
    script: str, *args: str, out: os.PathLike[str], timeout: float = 280
) -> tuple[subprocess.CompletedProcess, Any]:
    """Run ``benchmarks/<script> *args --out <out>``, check that it succeeded, and return the
    process and the JSON it wrote to ``out``.

    Raises:
        AssertionError: the script exited with a non-zero code (the message ends with its
            output).
    """
    proc = run_script(script, *args, "--out", str(out), timeout=timeout)
    assert proc.returncode == 0, proc.stdout[-OUTPUT_TAIL:] + proc.stderr[-OUTPUT_TAIL:]
    return proc, json.loads(Path(out).read_text())


def import_benchmarks(*names: str) -> tuple[ModuleType, ...]:
    """Import modules of ``benchmarks/`` (which is not a package) by name, in order."""
    import importlib

    sys.path.insert(0, str(BENCHMARKS))
    try:
        return tuple(importlib.import_module(name) for name in names)
    finally:
        sys.path.remove(str(BENCHMARKS))
