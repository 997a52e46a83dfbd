"""The documentation harness: every shell and Python block of README.md and docs/*.md runs.

`Sybil <https://sybil.readthedocs.io>`_ finds the fenced blocks and turns each into a pytest
item (``pytest README.md docs``); the convention for writers is in docs/contributing.md:

- ```` ```python ```` blocks run in one namespace per page, top to bottom;
- ```` ```bash ````, ```` ```sh ```` and ```` ```console ```` blocks run in bash (``set -eo
  pipefail``; in a console block only the ``$ `` lines), with ``.venv/bin`` first on PATH;
- ``<!-- skip: next "why" -->`` before a block (or ``skip: start "why"`` ... ``skip: end``
  around several) marks it as not runnable, the reason shown in pytest's summary;
- ``<!-- slow: next -->`` before a block marks it ``slow``: ``make test`` deselects it,
  ``.ci/run`` runs it (``pytest -m slow README.md docs``).

Every page runs in a fresh temporary folder holding links to the repository's top-level
entries (so ``plugins/...`` and ``.venv/bin/...`` resolve) but not to ``outputs/``: what a
block writes stays there. Dataset, data-cache and Hugging Face roots point into it too.

Fast mode (``EMBODICHAIN_DOCS_FAST``, on unless set to ``0``) shortens what the CLI runs:
``embodichain run-env`` gets ``--max_steps 8 --max_episodes 2`` appended, ``train-rl``
``--steps 64 --num_envs 2 --max_episode_steps 8`` (``--episodes 1`` with ``--play``),
``eval-policy`` ``--episodes 1 --max_steps 8`` and ``generate`` ``--episodes 2`` (the last
flag given wins with argparse). The commands themselves, their configs and flags are the
documented ones.
"""

from __future__ import annotations

import ctypes
import doctest
import gc
import os
import re
import shutil
import subprocess
import sys
import tempfile
import types
from pathlib import Path
from typing import Any, Iterable

import pytest

try:  # the test extra; the other suites load this file too and run without it
    from sybil import Document, Example, Region, Sybil
    from sybil.integration.pytest import SybilItem
    from sybil.parsers.markdown import CodeBlockParser, PythonCodeBlockParser, SkipParser
    from sybil.parsers.markdown.lexers import DirectiveInHTMLCommentLexer
except ImportError:  # pragma: no cover - reported when a page is collected
    Sybil = None  # type: ignore[assignment,misc]

REPO = Path(__file__).resolve().parent
VENV = Path(sys.prefix)  # the environment running the tests (.venv under make)
#: Top-level entries a page's temporary folder does not link to (written by the blocks).
NOT_LINKED = {"outputs", "site", ".git", ".venv"}
FAST_ENV = "EMBODICHAIN_DOCS_FAST"
#: The info strings of the fenced blocks that run in bash.
SHELL_LANGUAGES = ("bash", "sh", "shell", "console")
#: Commands that change the machine rather than show the project: an unmarked block running
#: one fails at once, asking for a ``skip`` mark (the harness never installs or fetches).
ENVIRONMENT_CHANGING = re.compile(
    r"(pip3?|python3? -m pip)\s+(install|uninstall)|\bapt(-get)?\s|\bmake\s+(test|test-all|setup|clean|format)\b"
    r"|\bgit\s+(clone|push|commit)|\bcurl\s|\bwget\s"
)
#: Seconds one shell block may run.
SHELL_TIMEOUT_S = 600
#: What fast mode appends to an ``embodichain`` sub-command (the last flag wins).
FAST_ARGS = {
    "run-env": "--max_episodes 2",
    "generate": "--episodes 2",
    "eval-policy": "--episodes 1 --max_steps 8",
    "train-rl": "--steps 64 --num_envs 2 --max_episode_steps 8",
}
#: The ``embodichain`` wrapper of fast mode (bash; ``@REAL@`` is the installed script).
WRAPPER = """#!/usr/bin/env bash
# fast mode of the docs harness (conftest.py): shortens the documented command
extra=()
case "$1" in
{cases}
esac
if [ "$1" = train-rl ] && [[ " $* " == *" --play "* ]]; then extra=(--episodes 1); fi
exec "@REAL@" "$@" "${{extra[@]}}"
"""


def fast_mode() -> bool:
    """Whether the harness shortens the CLI's runs (``EMBODICHAIN_DOCS_FAST``, default on)."""
    return os.environ.get(FAST_ENV, "1").strip() not in ("0", "false", "no")


class SlowParser:
    """Reads ``<!-- slow: next -->`` and remembers where it ends (no item of its own)."""

    def __init__(self) -> None:
        self.lexer = DirectiveInHTMLCommentLexer("slow")

    def __call__(self, document: Document) -> Iterable[Region]:
        ends = []
        for lexed in self.lexer(document):
            if (lexed.lexemes["arguments"] or "").strip() != "next":
                line = document.text.count("\n", 0, lexed.start) + 1
                raise ValueError(f"{document.path}:{line}: the slow directive takes 'next' only: <!-- slow: next -->")
            ends.append(document.text.index("-->", lexed.end) + 3)  # a lexed directive ends before its -->
        document.slow_ends = ends  # type: ignore[attr-defined]
        return []


def _shadow_venv(work: Path, bin_dir: Path) -> None:
    """``work/.venv``: the real one, but its ``bin/embodichain`` is the fast-mode wrapper."""
    venv = work / ".venv"
    venv.mkdir()
    for entry in VENV.iterdir():
        if entry.name != "bin":
            (venv / entry.name).symlink_to(entry)
    (venv / "bin").mkdir()
    for entry in (VENV / "bin").iterdir():
        target = bin_dir / "embodichain" if entry.name == "embodichain" else entry
        (venv / "bin" / entry.name).symlink_to(target)


def _make_workdir() -> Path:
    """A temporary folder linking the repository's top-level entries, ``.venv`` shadowed."""
    work = Path(tempfile.mkdtemp(prefix="docs_harness_"))
    for entry in REPO.iterdir():
        if entry.name not in NOT_LINKED:
            (work / entry.name).symlink_to(entry)
    bin_dir = work / ".harness_bin"
    bin_dir.mkdir()
    real = VENV / "bin" / "embodichain"
    if fast_mode():
        cases = "\n".join(f"  {cmd}) extra=({args});;" for cmd, args in FAST_ARGS.items())
        (bin_dir / "embodichain").write_text(WRAPPER.format(cases=cases).replace("@REAL@", str(real)))
        (bin_dir / "embodichain").chmod(0o755)
    else:
        (bin_dir / "embodichain").symlink_to(real)
    _shadow_venv(work, bin_dir)
    return work


def _page_environ(work: Path) -> dict[str, str]:
    """The variables a page's blocks run with: roots in ``work``, nothing downloaded."""
    return {
        "EMBODICHAIN_DEFAULT_DATASET_ROOT": str(work / "outputs" / "datasets"),
        "EMBODICHAIN_CACHE_DIR": str(work / ".cache"),
        "HF_HOME": str(work / ".hf"),
        "HF_HUB_OFFLINE": "1",
        "HF_DATASETS_OFFLINE": "1",
        "RAY_USAGE_STATS_ENABLED": "0",
        "MPLBACKEND": "Agg",
        "PATH": f"{work / '.harness_bin'}:{work / '.venv' / 'bin'}:{os.environ.get('PATH', '')}",
    }


def _page_module(namespace: dict[str, Any]) -> str:
    """A module in ``sys.modules`` whose attributes are the page's namespace.

    A class a block defines then has an importable ``__module__``, as in a script, so what
    registers it by ``"module:Class"`` (``register_env``, gymnasium) finds it again.
    """
    name = f"docs_page_{len([m for m in sys.modules if m.startswith('docs_page_')])}"
    module = types.ModuleType(name)

    def lookup(attr: str) -> Any:
        try:
            return namespace[attr]
        except KeyError:
            raise AttributeError(attr) from None

    module.__dict__["__getattr__"] = lookup
    sys.modules[name] = module
    namespace["__name__"] = name
    return name


def setup_page(namespace: dict[str, Any]) -> None:
    """Before a page: its temporary folder becomes the working directory."""
    module = _page_module(namespace)
    work = _make_workdir()
    environ = _page_environ(work)
    namespace["__harness__"] = {
        "module": module,
        "work": work,
        "cwd": os.getcwd(),
        "saved": {k: os.environ.get(k) for k in environ},
    }
    os.environ.update(environ)
    os.chdir(work)


def teardown_page(namespace: dict[str, Any]) -> None:
    """After a page: close the envs its blocks left open, restore cwd and variables, clean up."""
    state = namespace.pop("__harness__")
    gym = sys.modules.get("gymnasium")
    env_types = (gym.Env, gym.vector.VectorEnv) if gym is not None else ()
    for value in list(namespace.values()):
        if env_types and isinstance(value, env_types):
            try:
                value.close()
            except Exception:  # noqa: BLE001 - an env a block closed already
                pass
    os.chdir(state["cwd"])
    for key, value in state["saved"].items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value
    shutil.rmtree(state["work"], ignore_errors=True)
    sys.modules.pop(state["module"], None)


def shell_commands(source: str, language: str) -> str:
    """The script of a block: a console block's ``$ `` lines (and their continuations)."""
    if language != "console":
        return source
    lines, continuing = [], False
    for line in source.splitlines():
        if line.startswith("$ ") or continuing:
            lines.append(line[2:] if line.startswith("$ ") and not continuing else line)
            continuing = line.rstrip().endswith("\\")
    return "\n".join(lines)


def evaluate_shell(example: Example) -> str | None:
    """Runs a shell block in bash in the page's folder; a non-zero exit fails it (the message)."""
    script = shell_commands(str(example.parsed), example.region.lexemes.get("arguments", "bash"))
    changing = ENVIRONMENT_CHANGING.search(script)
    if changing:
        return (
            f"{changing.group(0).strip()!r} would change this machine (install, fetch or rebuild): mark the "
            'block not runnable with <!-- skip: next "why" --> (docs/contributing.md)'
        )
    result = subprocess.run(
        ["bash", "-eo", "pipefail", "-c", script],
        capture_output=True,
        text=True,
        timeout=SHELL_TIMEOUT_S,
        env=dict(os.environ),
    )
    if result.returncode != 0:
        tail = (result.stdout + result.stderr)[-4000:]
        return f"exit {result.returncode} from:\n{script}\n--- output (tail) ---\n{tail}"
    return None


def _sybil_missing(file_path: Path, parent: Any) -> None:
    if file_path.suffix == ".md" and (file_path.name == "README.md" or file_path.parent.name == "docs"):
        raise pytest.UsageError("the docs harness needs Sybil: .venv/bin/pip install -e '.[test]'")


pytest_collect_file = (
    _sybil_missing
    if Sybil is None
    else Sybil(
        parsers=[
            SkipParser(),
            SlowParser(),
            PythonCodeBlockParser(doctest_optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE),
            *(CodeBlockParser(language=lang, evaluator=evaluate_shell) for lang in SHELL_LANGUAGES),
        ],
        patterns=["README.md", "docs/*.md"],
        setup=setup_page,
        teardown=teardown_page,
    ).pytest()
)


#: glibc, whose ``malloc_trim`` hands freed heap pages back to the system (None elsewhere).
def pytest_configure(config: pytest.Config) -> None:
    """Ctrl-C raises ``KeyboardInterrupt`` in the test process and its children, however the
    suite was started: a shell's background job (``make test &``, ``nohup``) starts with
    SIGINT ignored, and an ignored signal stays ignored across exec, so the Ctrl-C tests of
    the recorders and of ``generate`` would otherwise see nothing."""
    import signal

    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


_LIBC = ctypes.CDLL(None) if sys.platform.startswith("linux") else None


@pytest.fixture(autouse=True, scope="module")
def _release_memory_after_each_file() -> Iterable[None]:
    """After each test file (docs page): collect garbage and return the freed heap to the system.

    A test process runs many files; without this its resident memory only grows (freed memory
    stays in the allocator's arenas), about 30% above what the files need at once.
    """
    yield
    gc.collect()
    trim = getattr(_LIBC, "malloc_trim", None)
    if trim is not None:
        trim(0)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Marks ``slow`` the blocks that follow a ``<!-- slow: next -->``."""
    if Sybil is None:
        return
    for item in items:
        if not isinstance(item, SybilItem):
            continue
        document = item.example.document
        start = item.example.region.start
        if any(end <= start and not document.text[end:start].strip() for end in getattr(document, "slow_ends", ())):
            item.add_marker(pytest.mark.slow)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: Any) -> Any:
    """A skipped block is reported at its page and line (not where Sybil raised the skip)."""
    outcome = yield
    report = outcome.get_result()
    if Sybil is not None and isinstance(item, SybilItem) and report.skipped and isinstance(report.longrepr, tuple):
        report.longrepr = (str(item.path), item.example.line - 1, report.longrepr[2])
