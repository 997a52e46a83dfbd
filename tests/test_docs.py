"""The docs site: it builds strictly, its nav covers docs/, the CLI page is up to date, and
every hookspec, registered functor and registered task is documented.

The functor and task checks cover what the plugins of this repository (``plugins/*``)
register once installed; each is skipped while those plugins register nothing.

The docs must also agree with the code they describe (README.md and docs/*.md): every
``make X`` they show is a Makefile target and what they say ``make run`` does is the
Makefile's main job; the torch version they cite is the set-up script's; every
``embodichain <command> --flag`` they show is accepted by that command's parser; every
relative link resolves (README included, which mkdocs does not build); and every
``from embodichain... import X`` in their code blocks imports.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, Iterable

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
#: Pages of which at least one must name each hook specification.
HOOK_PAGES = ("plugins.md",)


def nav_pages(nav: Any) -> list[str]:
    """Every page file in an mkdocs ``nav`` (nested sections included)."""
    if isinstance(nav, str):
        return [nav]
    if isinstance(nav, list):
        return [page for item in nav for page in nav_pages(item)]
    if isinstance(nav, dict):
        return [page for value in nav.values() for page in nav_pages(value)]
    return []


def repo_plugin_names() -> set[str]:
    """Distribution (= provider) names of the plugins kept in plugins/."""
    names = set()
    for pyproject in REPO.glob("plugins/*/pyproject.toml"):
        match = re.search(r'^name\s*=\s*"([^"]+)"', pyproject.read_text(encoding="utf-8"), re.MULTILINE)
        names.update([match.group(1)] if match else [])
    return names


def undocumented(names: Iterable[str], page: Path) -> list[str]:
    """The names that do not appear in ``page`` as whole words."""
    text = page.read_text(encoding="utf-8") if page.exists() else ""
    return sorted(n for n in names if not re.search(rf"(?<![\w-]){re.escape(n)}(?![\w-])", text))


def registered(kind: str) -> list[str]:
    """Names of ``kind`` registered by this repository's plugins (installed and loaded)."""
    from embodichain_core.plugins import get_registry

    providers = repo_plugin_names()
    return [e.name for e in get_registry(kind).entries() if e.provider in providers]


def load_generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_cli_docs", REPO / "scripts" / "gen_cli_docs.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_nav_lists_every_page_once() -> None:
    config = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    listed = nav_pages(config["nav"])
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")}
    assert not sorted(pages - set(listed)), f"add {sorted(pages - set(listed))} to the nav in mkdocs.yml"
    assert not sorted(set(listed) - pages), f"the nav in mkdocs.yml lists missing pages {sorted(set(listed) - pages)}"
    assert len(listed) == len(set(listed)), "a page is listed twice in the nav"


def test_mkdocs_build_is_strict_and_passes(tmp_path: Path) -> None:
    pytest.importorskip("mkdocs", reason="mkdocs is in the test extra")
    config = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    assert config["strict"] is True
    assert config["theme"]["name"] == "material"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    out = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert out.returncode == 0, f"mkdocs build --strict failed:\n{out.stdout}\n{out.stderr}"
    assert (tmp_path / "site" / "plugins" / "index.html").is_file()


def test_cli_reference_is_generated_from_the_parsers() -> None:
    generated = load_generator().render()
    committed = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert committed == generated, "docs/cli.md is out of date: run .venv/bin/python scripts/gen_cli_docs.py"


def test_cli_reference_covers_every_builtin_command_and_option() -> None:
    from embodichain_core.cli import new_cmd
    from embodichain_core.plugins.builtin import BUILTIN_COMMANDS

    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert all(f"## `embodichain {name}`" in text for name in BUILTIN_COMMANDS)
    for sub in ("task", "functor"):
        assert f"### `embodichain new {sub}`" in text
    assert "`--no-input`" in text
    assert "`--kind`" in text
    assert "`-o`, `--output-dir` `DIR`" in text
    assert new_cmd.build_parser().prog == "embodichain new"


def test_every_hookspec_is_documented() -> None:
    from embodichain_core.plugins import hookspecs

    specs = [
        name
        for name, obj in vars(hookspecs).items()
        if callable(obj) and getattr(obj, "embodichain_spec", None) is not None
    ]
    assert len(specs) >= 6
    missing = set(specs)
    for page in HOOK_PAGES:
        missing &= set(undocumented(specs, DOCS / page))
    assert not missing, f"neither of docs/{' and docs/'.join(HOOK_PAGES)} names the hook(s) {sorted(missing)}"


def test_every_registered_functor_is_in_the_catalogue() -> None:
    names = registered("functors")
    if not names:
        pytest.skip("no functor registered by the plugins in plugins/ (none installed yet)")
    missing = undocumented(names, DOCS / "functor_catalogue.md")
    assert not missing, f"docs/functor_catalogue.md does not list the functor(s) {missing}"


def test_every_registered_task_is_in_the_task_list() -> None:
    names = registered("tasks")
    if not names:
        pytest.skip("no task registered by the plugins in plugins/ (none installed yet)")
    missing = undocumented(names, DOCS / "tasks.md")
    assert not missing, f"docs/tasks.md does not list the task(s) {missing}"


def test_meta_checks_catch_a_missing_name(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("`randomize_light` and PushCube-v1, see `joint_pos_rel`.\n")
    assert undocumented(["randomize_light", "PushCube-v1", "joint_pos", "PushCube-v10"], page) == [
        "PushCube-v10",
        "joint_pos",
    ]
    assert undocumented(["anything"], tmp_path / "absent.md") == ["anything"]


# -- the docs agree with the Makefile, the set-up script and the code ---------------------------

#: Pages checked against the code: the README and every page of the site.
CHECKED_PAGES = (REPO / "README.md", *sorted(DOCS.glob("*.md")))
_FENCE = re.compile(r"^\s*(```|~~~)")


def rel(page: Path) -> str:
    """``page`` relative to the repository (its name when outside it)."""
    return page.relative_to(REPO).as_posix() if page.is_relative_to(REPO) else page.name


def split_markdown(text: str) -> tuple[list[tuple[int, str]], list[tuple[int, str]]]:
    """``(code_lines, prose_lines)``: ``(line number, text)`` inside fenced code blocks, and outside."""
    code, prose, fenced = [], [], False
    for number, line in enumerate(text.splitlines(), 1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        (code if fenced else prose).append((number, line))
    return code, prose


def inline_code(line: str) -> list[str]:
    """The contents of the `inline code` spans of a prose line."""
    return re.findall(r"`([^`\n]+)`", line)


def prose_units(prose: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """Prose as ``(first line, text)`` units: paragraphs (joined lines), and each table row alone."""
    units: list[tuple[int, str]] = []
    current: list[tuple[int, str]] = []

    def flush() -> None:
        if current:
            units.append((current[0][0], " ".join(line.strip() for _, line in current)))
            current.clear()

    for number, line in prose:
        if not line.strip() or line.lstrip().startswith(("|", "#")):
            flush()
            if line.strip():
                units.append((number, line))
            continue
        current.append((number, line))
    flush()
    return units


def sentences(text: str) -> list[str]:
    """``text`` split into sentences (at ``.``/``!``/``?`` followed by a capital, ``` ` ``` or ``[``)."""
    return re.split(r"(?<=[.!?)])\s+(?=[A-Z`\[*])", text)


# -- make targets ------------------------------------------------------------------------------------


def makefile_targets() -> set[str]:
    """The targets the Makefile defines (``name:`` rules; variables and ``$(STAMP)`` left out)."""
    text = (REPO / "Makefile").read_text(encoding="utf-8")
    return set(re.findall(r"^([A-Za-z][\w-]*)\s*:(?!=)", text, re.MULTILINE))


_MAKE = re.compile(r"^\s*(?:\$\s+)?(?:[A-Z_]+=\S*\s+)*make\s+([A-Za-z][\w-]*)")


def documented_make_targets(page: Path) -> list[tuple[int, str]]:
    """``(line, target)`` of every ``make X`` command in ``page``: code lines and inline code."""
    code, prose = split_markdown(page.read_text(encoding="utf-8"))
    found = [(n, m.group(1)) for n, line in code if (m := _MAKE.match(line))]
    found += [(n, m.group(1)) for n, line in prose for span in inline_code(line) if (m := _MAKE.match(span))]
    return found


def test_every_documented_make_target_exists() -> None:
    targets = makefile_targets()
    assert {"run", "test", "setup", "bench", "docs", "clean", "test-all"} <= targets, targets
    documented = [(page, n, target) for page in CHECKED_PAGES for n, target in documented_make_targets(page)]
    assert {"run", "test"} <= {target for *_, target in documented}, "the docs show no `make run`/`make test`"
    missing = [f"{rel(page)}:{n}: make {target}" for page, n, target in documented if target not in targets]
    assert not missing, f"documented make targets the Makefile does not define: {missing}"


def main_job() -> tuple[str, dict[str, Any], str, str]:
    """``(config path, config, comment, command)`` of the Makefile's main job (``make run``).

    ``comment`` is the comment block above ``MAIN_JOB``; ``command`` the ``run`` recipe with
    ``$(VENV)/bin/`` dropped and ``$(MAIN_JOB)`` expanded, as the docs write it.
    """
    text = (REPO / "Makefile").read_text(encoding="utf-8")
    match = re.search(r"((?:^#.*\n)+)MAIN_JOB\s*:=\s*(\S+)\s*$", text, re.MULTILINE)
    assert match, "the Makefile defines no MAIN_JOB with a comment above it"
    comment, path = " ".join(line.lstrip("# ") for line in match.group(1).splitlines()), match.group(2)
    recipe = re.search(r"^run:.*\n\t(.+)$", text, re.MULTILINE)
    assert recipe, "the Makefile has no run target"
    command = recipe.group(1).replace("$(VENV)/bin/", "").replace("$(MAIN_JOB)", path).strip()
    assert path in command, "`make run` does not run $(MAIN_JOB)"
    return path, json.loads((REPO / path).read_text(encoding="utf-8")), comment, command


def make_run_mentions(page: Path) -> list[tuple[int, str]]:
    """``(line, unit)`` of each code line or prose unit (paragraph, table row) naming ``make run``."""
    code, prose = split_markdown(page.read_text(encoding="utf-8"))
    units = [(n, line) for n, line in code if _MAKE.match(line) and _MAKE.match(line).group(1) == "run"]
    return units + [(n, unit) for n, unit in prose_units(prose) if "make run" in unit]


def test_make_run_is_documented_as_the_makefile_main_job() -> None:
    path, config, comment, command = main_job()
    task_id, num_envs = config["id"], config["num_envs"]
    message = f"the Makefile's MAIN_JOB comment does not describe {path} ({task_id}, {num_envs} envs): {comment!r}"
    assert task_id in comment, message
    assert f"{num_envs} envs" in comment, message
    mentions = [(page, n, unit) for page in CHECKED_PAGES for n, unit in make_run_mentions(page)]
    assert len({page for page, *_ in mentions}) >= 2, "README and getting_started must say what `make run` does"
    wrong = []
    for page, n, unit in mentions:
        if task_id not in unit:
            wrong.append(f"{rel(page)}:{n}: does not name the main job's task {task_id}: {unit!r}")
        for sentence in sentences(unit):
            if "make run" in sentence and "demo scene" in sentence:
                wrong.append(
                    f"{rel(page)}:{n}: `make run` is the main job ({task_id}), not the demo scene: {sentence!r}"
                )
        for shown in re.findall(r"`make run` is `([^`]+)`", unit):
            if shown != command:
                wrong.append(f"{rel(page)}:{n}: `make run` is `{command}` (Makefile), not `{shown}`")
    assert not wrong, "\n".join(wrong)


# -- versions ----------------------------------------------------------------------------------------


def setup_versions() -> dict[str, str]:
    """Default versions in scripts/setup_env.sh: ``{"torch": ..., "torchvision": ...}``."""
    text = (REPO / "scripts" / "setup_env.sh").read_text(encoding="utf-8")
    versions = {}
    for package in ("torch", "torchvision"):
        var = f"{package.upper()}_VERSION"
        match = re.search(rf"^{var}=\$\{{{var}:-([\d.]+)\}}", text, re.MULTILINE)
        assert match, f"scripts/setup_env.sh sets no default {var}"
        versions[package] = match.group(1)
    return versions


_CITED = re.compile(r"(?<![\w-])(torch|torchvision)(?:==|\s+)v?(\d+\.\d+(?:\.\d+)?)\b")
_CITED_VAR = re.compile(r"`(TORCH|TORCHVISION)_VERSION`, default `([\d.]+)`")


def cited_versions(page: Path) -> list[tuple[int, str, str]]:
    """``(line, package, version)`` of every torch/torchvision version ``page`` cites."""
    found = []
    for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        found += [(number, package, version) for package, version in _CITED.findall(line)]
        found += [(number, var.lower(), version) for var, version in _CITED_VAR.findall(line)]
    return found


def same_release(cited: str, actual: str) -> bool:
    """``2.10`` and ``2.10.0`` cite ``2.10.0``; ``2.13`` does not."""
    return actual.split(".")[: len(cited.split("."))] == cited.split(".")


def test_cited_torch_versions_are_the_set_up_s() -> None:
    versions = setup_versions()
    cited = [(page, *c) for page in CHECKED_PAGES for c in cited_versions(page)]
    assert any(page.name == "getting_started.md" and package == "torch" for page, _, package, _ in cited), (
        "docs/getting_started.md no longer cites the torch version the set-up installs"
    )
    wrong = [
        f"{rel(page)}:{n}: {package} {version} (scripts/setup_env.sh installs {versions[package]})"
        for page, n, package, version in cited
        if not same_release(version, versions[package])
    ]
    assert not wrong, "docs cite versions the set-up does not install:\n" + "\n".join(wrong)


def test_the_documented_set_up_variables_exist() -> None:
    """Every ``TORCH_*`` variable the docs tell users to set is read by scripts/setup_env.sh."""
    script = (REPO / "scripts" / "setup_env.sh").read_text(encoding="utf-8")
    documented = {
        var
        for page in CHECKED_PAGES
        for var in re.findall(r"\b(TORCH\w*_(?:VERSION|URL))\b", page.read_text(encoding="utf-8"))
    }
    assert "TORCH_INDEX_URL" in documented, "README/getting_started no longer document TORCH_INDEX_URL"
    missing = sorted(var for var in documented if not re.search(rf"\${{{var}\b|\${var}\b", script))
    assert not missing, f"scripts/setup_env.sh does not read {missing}"


# -- CLI flags ---------------------------------------------------------------------------------------


def command_parsers() -> dict[str, argparse.ArgumentParser]:
    """The parser of every installed ``embodichain`` command whose module has ``build_parser``."""
    from embodichain_core.plugins import command_registry

    generator = load_generator()
    parsers = {}
    for entry in command_registry().entries():
        target = entry.target if isinstance(entry.target, str) else ""
        parser = generator.command_parser(target) if target else None
        if parser is not None:
            parsers[entry.name] = parser
    return parsers


def invocations(page: Path) -> list[tuple[int, str]]:
    """``(line, command line)`` of every ``embodichain ...`` command ``page`` shows.

    Code lines (a ``$ `` prompt, a ``.venv/bin/`` prefix and a ``# comment`` dropped; an
    indented ``[...`` usage line right below continues the line) and inline code.
    """
    code, prose = split_markdown(page.read_text(encoding="utf-8"))
    found: list[tuple[int, str]] = []
    for number, line in code:
        stripped = re.sub(r"^\s*(?:\$\s+)?(?:\S*/bin/)?", "", line)
        if stripped.startswith("embodichain "):
            found.append((number, stripped.split(" #")[0].rstrip()))
        elif found and found[-1][0] < number and re.match(r"^\s+\[", line) and number - found[-1][0] <= 3:
            found[-1] = (found[-1][0], f"{found[-1][1]} {line.strip()}")
    for number, line in prose:
        for span in inline_code(line):
            span = re.sub(r"^(?:\S*/bin/)", "", span)
            if span.startswith("embodichain "):
                found.append((number, span))
    return found


def bad_flags(command_line: str, parsers: dict[str, argparse.ArgumentParser]) -> list[str]:
    """The options of ``command_line`` that its command (and subcommand) does not accept."""
    tokens = [t.strip("[](){},'\"`|") for t in command_line.split()[1:]]
    if not tokens or tokens[0] not in parsers:
        return []  # a placeholder (<command>), an output line ("embodichain new: error: ..."), a plugin's
    parser = parsers[tokens[0]]
    valid = {o for a in parser._actions for o in a.option_strings}
    bad = []
    for token in tokens[1:]:
        subs = {
            name: sub
            for a in parser._actions
            if isinstance(a, argparse._SubParsersAction)
            for name, sub in a.choices.items()
        }
        if token in subs:
            parser = subs[token]
            valid |= {o for a in parser._actions for o in a.option_strings}
        elif re.match(r"^--?[A-Za-z]", token) and token.split("=")[0] not in valid:
            bad.append(token.split("=")[0])
    return bad


def test_every_documented_cli_flag_exists() -> None:
    parsers = command_parsers()
    assert {"run-env", "list", "new", "decompose", "bench"} <= set(parsers)
    shown = [(page, n, line) for page in CHECKED_PAGES if page.name != "cli.md" for n, line in invocations(page)]
    assert sum(" --" in line for *_, line in shown) >= 10, "too few documented commands found: the parsing broke"
    wrong = [f"{rel(page)}:{n}: {flag} in {line!r}" for page, n, line in shown for flag in bad_flags(line, parsers)]
    assert not wrong, "documented options the commands do not accept:\n" + "\n".join(wrong)


def test_flag_check_catches_a_wrong_flag() -> None:
    parsers = command_parsers()
    assert bad_flags("embodichain run-env --num_envs 2 --num-envs 3 [--renderer R]", parsers) == ["--num-envs"]
    assert bad_flags("embodichain new functor x --kind event -o out --task-id X-v0", parsers) == ["--task-id"]
    assert bad_flags("embodichain new task x --task-id X-v0", parsers) == []
    assert bad_flags("embodichain new: error: invalid --anything", parsers) == []


# -- links -------------------------------------------------------------------------------------------


def slugify(title: str) -> str:
    """The anchor Python-Markdown's ``toc`` extension gives a heading (its default slugify)."""
    import unicodedata

    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title).replace("`", "")
    title = unicodedata.normalize("NFKD", title).encode("ascii", "ignore").decode("ascii")
    title = re.sub(r"[^\w\s-]", "", title).strip().lower()
    return re.sub(r"[-\s]+", "-", title)


def anchors(page: Path) -> set[str]:
    """The heading anchors of ``page`` (duplicates get ``_1``, ``_2``... as in ``toc``)."""
    _, prose = split_markdown(page.read_text(encoding="utf-8"))
    seen: set[str] = set()
    for _, line in prose:
        match = re.match(r"^#{1,6}\s+(.+?)\s*#*\s*$", line)
        if match:
            slug, count = slugify(match.group(1)), 1
            while slug in seen:
                slug, count = f"{slugify(match.group(1))}_{count}", count + 1
            seen.add(slug)
    return seen


def broken_links(page: Path) -> list[str]:
    """The relative links (and images) of ``page`` whose file or heading anchor does not exist."""
    _, prose = split_markdown(page.read_text(encoding="utf-8"))
    broken = []
    for number, line in prose:
        line = re.sub(r"`[^`]*`", "", line)
        for target in re.findall(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", line):
            if re.match(r"^[a-z][\w+.-]*:", target):  # http:, https:, mailto:
                continue
            path, _, anchor = target.partition("#")
            resolved = (page.parent / path).resolve() if path else page
            if not resolved.exists():
                broken.append(f"{rel(page)}:{number}: {target} (no such file)")
            elif anchor and resolved.suffix == ".md" and anchor not in anchors(resolved):
                broken.append(f"{rel(page)}:{number}: {target} (no heading #{anchor} in {resolved.name})")
    return broken


def test_every_relative_link_resolves() -> None:
    broken = [link for page in CHECKED_PAGES for link in broken_links(page)]
    assert not broken, "broken links:\n" + "\n".join(broken)


def test_link_check_catches_a_broken_link(tmp_path: Path) -> None:
    (tmp_path / "a.md").write_text("# A page\n\n## The `main` job\n\ntext\n")
    page = tmp_path / "b.md"
    page.write_text(
        "[ok](a.md#the-main-job) [self](#b) [gone](gone.md) [bad](a.md#nope) "
        "[web](https://example.org) `[code](x.md)`\n\n# B\n"
    )
    assert [link.split(": ", 1)[1] for link in broken_links(page)] == [
        "gone.md (no such file)",
        "a.md#nope (no heading #nope in a.md)",
    ]


# -- documented imports ------------------------------------------------------------------------------


def repo_packages() -> set[str]:
    """Top-level packages of the core and of the plugins kept in plugins/."""
    plugin_packages = {p.parent.name for p in REPO.glob("plugins/*/*/__init__.py")}
    return {"embodichain_core", *plugin_packages}


_IMPORT = re.compile(
    r"^[ \t]*(from[ \t]+([\w.]+)[ \t]+import[ \t]+(?:\([^)]*\)|[^\n#]+)|import[ \t]+([\w.]+)(?:[ \t]+as[ \t]+\w+)?)",
    re.MULTILINE,
)


def documented_imports(page: Path) -> list[tuple[int, str]]:
    """``(line, statement)`` of every import of a repository package in ``page``'s code blocks."""
    text = page.read_text(encoding="utf-8")
    code, _ = split_markdown(text)
    block = "\n".join(line for _, line in code)
    numbers = [n for n, _ in code]
    packages = repo_packages()
    found = []
    for match in _IMPORT.finditer(block):
        module = match.group(2) or match.group(3)
        statement = " ".join(match.group(1).split())
        if module.split(".")[0] in packages and "{{" not in statement:
            found.append((numbers[block.count("\n", 0, match.start())], statement))
    return found


def test_every_documented_import_works() -> None:
    """Each public name the docs import (``from embodichain_core... import X``) imports."""
    statements = [(rel(page), n, stmt) for page in CHECKED_PAGES for n, stmt in documented_imports(page)]
    assert len(statements) >= 30, f"only {len(statements)} documented imports found: the parsing broke"
    script = (
        "import json, sys\n"
        "failed = []\n"
        "for where, statement in json.loads(sys.argv[1]):\n"
        "    try:\n"
        "        exec(statement, {})\n"
        "    except Exception as err:\n"
        "        failed.append(f'{where}: {statement}: {type(err).__name__}: {err}')\n"
        "print(json.dumps(failed))\n"
    )
    payload = json.dumps([(f"{page}:{n}", stmt) for page, n, stmt in statements])
    out = subprocess.run(
        [sys.executable, "-c", script, payload], capture_output=True, text=True, timeout=300, check=False, cwd=REPO
    )
    assert out.returncode == 0, out.stderr
    failed = json.loads(out.stdout.strip().splitlines()[-1])
    assert not failed, "documented imports that fail:\n" + "\n".join(failed)


def test_import_check_finds_multiline_imports(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text(
        "```python\nfrom embodichain_core.plugins import (\n    get_functor, list_plugins,\n)\n"
        "import embodichain_core.gym_utils as gu\nfrom other_pkg import x\n```\n"
        "from embodichain_core import not_in_a_code_block\n"
    )
    assert documented_imports(page) == [
        (2, "from embodichain_core.plugins import ( get_functor, list_plugins, )"),
        (5, "import embodichain_core.gym_utils as gu"),
    ]
