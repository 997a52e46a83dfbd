"""The docs harness (conftest.py at the repository root) on a page of its own: unmarked blocks
run and fail on drift, ``skip`` and ``slow`` marks do what docs/contributing.md says, a block
that would install something is refused, and a page's files stay in its temporary folder.

Each case runs pytest in a subprocess on a scratch copy of the harness (a folder holding
conftest.py and docs/page.md), so the repository's own docs are not involved.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

PAGE = """# A page

<!-- skip: next "shows a placeholder" -->
```python
raise RuntimeError("a skipped block ran")
```

```python
import json

values = json.loads("[1, 2]")
```

```python
>>> sum(values)
3
>>> int("x")
Traceback (most recent call last):
ValueError: invalid literal for int() with base 10: 'x'
```

```console
$ echo made > made.txt
made
```

<!-- slow: next -->
```bash
test -f made.txt
```
"""


def run_harness(tmp_path: Path, page: str, *args: str) -> dict[str, str]:
    """Run the harness on ``page``; the outcome of each block by its line (``{"5": "passed"}``)."""
    root = tmp_path / "site"
    (root / "docs").mkdir(parents=True, exist_ok=True)
    shutil.copy(REPO / "conftest.py", root / "conftest.py")
    (root / "pyproject.toml").write_text('[tool.pytest.ini_options]\nmarkers = ["slow: long"]\n')
    (root / "docs" / "page.md").write_text(page)
    report = tmp_path / "report.json"
    plugin = tmp_path / "outcomes.py"
    plugin.write_text(
        "import json\nOUT = {}\n"
        "def pytest_runtest_logreport(report):\n"
        "    if report.when == 'call' or report.outcome != 'passed':\n"
        "        OUT[report.nodeid.split('line:')[1].split(',')[0]] = report.outcome\n"
        f"def pytest_sessionfinish(session):\n    open({str(report)!r}, 'w').write(json.dumps(OUT))\n"
    )
    env = {"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "outcomes", "-p", "no:cacheprovider", "docs", *args],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert report.exists(), result.stdout + result.stderr
    return json.loads(report.read_text())


def test_unmarked_blocks_run_and_marks_skip_or_defer(tmp_path: Path) -> None:
    outcomes = run_harness(tmp_path, PAGE, "-m", "not slow")
    assert outcomes.pop("4") == "skipped"  # skip: next (the directive itself, line 3, passes)
    assert outcomes == {"3": "passed", "8": "passed", "15": "passed", "17": "passed", "22": "passed"}
    assert not list((tmp_path / "site").glob("made.txt"))  # written in the page's own folder
    outcomes = run_harness(tmp_path, PAGE, "-m", "slow")
    assert outcomes == {"28": "failed"}  # alone, the slow block misses what the page made before it


@pytest.mark.parametrize(
    "block",
    [
        "```python\nassert 1 + 1 == 3\n```\n",
        "```python\n>>> 1 + 1\n3\n```\n",
        "```bash\nfalse\n```\n",
        "```console\n$ ls no-such-file\n```\n",
        "```bash\npip install --help\n```\n",  # refused (would pass if run)
    ],
)
def test_a_drifted_or_unsafe_block_fails(tmp_path: Path, block: str) -> None:
    assert list(run_harness(tmp_path, "# A page\n\n" + block).values()) == ["failed"]
