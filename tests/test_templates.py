"""The plugin templates and ``embodichain new``.

Each template is baked into ``tmp_path``, the baked package is pip-installed into a folder of
``tmp_path`` only (``pip install --target``), its own tests run in a subprocess with that folder
on ``PYTHONPATH``, and such a fresh interpreter discovers it through its entry point
(``gym.make`` for the task). The environment running the tests never sees the baked packages:
neither this interpreter nor another process of the environment (``embodichain list tasks`` run
meanwhile), which the tests check while and after the packages are installed. Bad names fail
before anything is written.
"""

from __future__ import annotations

import importlib.metadata
import os
import shutil
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest

from embodichain_core.cli import new_cmd
from embodichain_core.templates import TEMPLATES, names, template_dir

REPO = Path(__file__).resolve().parents[1]
#: Names unlikely to clash with anything another test or plugin registers.
TASK_NAME, TASK_ID, TASK_DIST = "tmpl_reach", "TmplReach-v0", "embodichain-tmpl-reach"
FUNCTOR_KINDS = ("observation", "reward", "event", "randomization")


def run(args: list[str], cwd: Path | None = None, timeout: float = 300, **env_vars: str) -> subprocess.CompletedProcess:
    """Run ``args`` (with ``env_vars`` set); fail the test with the output when it exits non-zero."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", **env_vars}
    out = subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)
    assert out.returncode == 0, f"{' '.join(args)} exited {out.returncode}:\n{out.stdout}\n{out.stderr}"
    return out


#: Distribution-name prefixes of every package these tests bake.
BAKED_PREFIXES = ("embodichain-tmpl-", "embodichain-randomize-tmpl-")


def baked_distributions(names: list[str]) -> list[str]:
    """The names in ``names`` of packages these tests bake."""
    return sorted(n for n in names if n.lower().startswith(BAKED_PREFIXES))


def assert_environment_untouched() -> None:
    """No baked package is visible to this interpreter or to a fresh one of this environment."""
    importlib.invalidate_caches()
    here = baked_distributions([d.metadata["Name"] or "" for d in importlib.metadata.distributions()])
    assert here == [], f"baked packages visible to the test process: {here}"
    code = "import importlib.metadata as m; print(*(d.metadata['Name'] for d in m.distributions()))"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    fresh = baked_distributions(out.stdout.split())
    assert fresh == [], f"baked packages installed into the environment {sys.prefix}: {fresh}"


@contextmanager
def installed(site: Path, *package_dirs: Path) -> Iterator[dict[str, str]]:
    """pip-install the baked packages (no deps) into the folder ``site`` only, for the block.

    A baked package's directory is named after its distribution.

    Yields:
        The environment variables under which a subprocess sees the packages (``PYTHONPATH``).
    """
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    run([*pip, "install", "--no-deps", "--no-build-isolation", "--target", str(site), *map(str, package_dirs)])
    found = baked_distributions([p.name.split("-")[0].replace("_", "-") for p in site.glob("*.dist-info")])
    assert found == sorted(d.name for d in package_dirs), f"not installed into {site}: {found}"
    paths = [str(site), *([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])]
    try:
        assert_environment_untouched()
        yield {"PYTHONPATH": os.pathsep.join(paths)}
    finally:
        shutil.rmtree(site, ignore_errors=True)
    assert_environment_untouched()


def new(*argv: str) -> int:
    """``embodichain new ARGV...`` in-process; returns the exit code."""
    return new_cmd.main(list(argv))


# -- names ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, expected",
    [
        ("push_cube", ("embodichain-push-cube", "embodichain_push_cube", "PushCube", "PushCube-v0")),
        ("push-cube", ("embodichain-push-cube", "embodichain_push_cube", "PushCube", "PushCube-v0")),
        ("PushCube2", ("embodichain-pushcube2", "embodichain_pushcube2", "PushCube2", "PushCube2-v0")),
    ],
)
def test_task_names_derive_from_one_name(name: str, expected: tuple[str, ...]) -> None:
    ctx = names.task_context(name)
    assert (ctx["distribution_name"], ctx["package_name"], ctx["class_name"], ctx["task_id"]) == expected
    assert names.validate_task_context(ctx) == []


@pytest.mark.parametrize("template, name", [("task", "push_cube"), ("task", "Push-Cube3"), ("functor", "cube_height")])
def test_cookiecutter_defaults_match_the_python_derivation(template: str, name: str) -> None:
    from cookiecutter.generate import generate_context
    from cookiecutter.prompt import prompt_for_config

    key = "task_name" if template == "task" else "functor_name"
    context = generate_context(str(template_dir(template) / "cookiecutter.json"), extra_context={key: name})
    rendered = prompt_for_config(context, no_input=True)
    derived = names.task_context(name) if template == "task" else names.functor_context(name, "observation")
    assert {k: rendered[k] for k in derived} == derived


@pytest.mark.parametrize("kind", FUNCTOR_KINDS)
def test_functor_template_describes_each_kind_by_what_it_bakes(kind: str) -> None:
    """The default description (registration, docstring, README) is the one of ``kind``'s example,
    not the observation's "Position of an object" for every kind."""
    from cookiecutter.generate import generate_context
    from cookiecutter.prompt import prompt_for_config

    name = "randomize_cube" if kind == "randomization" else "cube_thing"
    context = generate_context(
        str(template_dir("functor") / "cookiecutter.json"), extra_context={"functor_name": name, "kind": kind}
    )
    rendered = prompt_for_config(context, no_input=True)
    assert rendered["kind"] == kind
    assert rendered["description"] == names.FUNCTOR_DESCRIPTIONS[kind]
    assert names.functor_context(name, kind)["description"] == names.FUNCTOR_DESCRIPTIONS[kind]
    assert ("Position" in rendered["description"]) is (kind == "observation")


def test_functor_descriptions_are_one_per_kind() -> None:
    assert set(names.FUNCTOR_DESCRIPTIONS) == set(FUNCTOR_KINDS) == set(names.FUNCTOR_KINDS)
    assert len(set(names.FUNCTOR_DESCRIPTIONS.values())) == len(FUNCTOR_KINDS)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["task", "my-task!"], "invalid task name 'my-task!'"),
        (["task", "9lives"], "invalid task name '9lives'"),
        (["task", "my_task", "--task-id", "MyTask"], "invalid task id 'MyTask'"),
        (["task", "my_task", "--task-id", "My Task-v0"], "invalid task id 'My Task-v0'"),
        (
            ["task", "reach_target", "--task-id", "acme/ReachTarget-v0"],
            "invalid task id 'acme/ReachTarget-v0': give it without a namespace ('ReachTarget-v0'); the gym "
            "namespace is always the distribution that provides the task, so it is registered as "
            "'embodichain-reach-target/ReachTarget-v0'",
        ),
        (["task", "my_task", "--max-episode-steps", "0"], "invalid max_episode_steps 0"),
        (["functor", "Cube-Height", "--kind", "reward"], "invalid functor name 'Cube-Height'"),
        (["functor", "class", "--kind", "event"], "invalid functor name 'class'"),
    ],
)
def test_cli_rejects_bad_names_before_writing(
    argv: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert new(*argv, "--no-input", "-o", str(tmp_path)) == 2
    err = capsys.readouterr().err
    assert f"embodichain new: error: {message}" in err
    assert list(tmp_path.iterdir()) == []


def test_template_hook_rejects_bad_names_typed_at_the_prompts(tmp_path: Path) -> None:
    from cookiecutter.exceptions import FailedHookException

    for template, context in (
        ("task", {"task_name": "ok_name", "task_id": "NoVersion"}),
        ("functor", {"functor_name": "cube_mass", "kind": "randomization"}),
    ):
        with pytest.raises(FailedHookException):
            new_cmd.bake(template, context, tmp_path)
        assert list(tmp_path.iterdir()) == []


def test_randomization_functors_get_the_prefix(tmp_path: Path) -> None:
    assert new("functor", "cube_mass", "--kind", "randomization", "--no-input", "-o", str(tmp_path)) == 0
    package = tmp_path / "embodichain-randomize-cube-mass"
    plugin = (package / "embodichain_randomize_cube_mass" / "plugin.py").read_text()
    assert 'FUNCTOR_NAME = "randomize_cube_mass"' in plugin
    assert '"randomization.physics"' in plugin


def test_existing_package_dir_needs_overwrite(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ("task", "twice", "--no-input", "-o", str(tmp_path))
    assert new(*args) == 0
    assert new(*args) == 1
    assert "pass --overwrite" in capsys.readouterr().err
    assert new(*args, "--overwrite", "--description", "Second") == 0
    assert "(Second)" in (tmp_path / "embodichain-twice" / "pyproject.toml").read_text()


# -- packaging -----------------------------------------------------------------------------


def test_templates_ship_in_the_core_package() -> None:
    tomllib = pytest.importorskip("tomllib")
    for name in TEMPLATES:
        assert (template_dir(name) / "cookiecutter.json").is_file()
        assert (template_dir(name) / "hooks" / "pre_gen_project.py").is_file()
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert config["package-dir"]["embodichain_core.templates"] == "templates"
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    # cookiecutter is only for `embodichain new`: the `new` extra, not a core dependency
    assert not any(dep.startswith("cookiecutter") for dep in project["dependencies"])
    assert any(dep.startswith("cookiecutter") for dep in project["optional-dependencies"]["new"])


def test_new_without_cookiecutter_names_the_extra(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without cookiecutter (the `new` extra), `embodichain new` exits 1 naming the install command."""
    for module in [m for m in sys.modules if m == "cookiecutter" or m.startswith("cookiecutter.")]:
        monkeypatch.delitem(sys.modules, module)
    monkeypatch.setitem(sys.modules, "cookiecutter", None)  # `import cookiecutter...` raises ImportError
    assert new("functor", "cube_height", "--no-input", "-o", str(tmp_path)) == 1
    err = capsys.readouterr().err
    assert 'pip install "embodichain-core[new]"' in err
    assert err.startswith("embodichain new: error: cookiecutter is not installed")
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(new_cmd.MissingTemplateEngineError, match=r"embodichain-core\[new\]"):
        new_cmd.bake("functor", {"functor_name": "cube_height"}, tmp_path)
    assert new("functor", "Bad-Name", "--no-input", "-o", str(tmp_path)) == 2  # names are still checked first


def test_pyproject_lists_every_core_package() -> None:
    """``packages`` is an explicit list (for the templates mapping): new packages must be added."""
    tomllib = pytest.importorskip("tomllib")
    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {
        ".".join(p.relative_to(REPO).parts)
        for p in (REPO / "embodichain_core").rglob("*")
        if p.is_dir() and p.name != "__pycache__" and any(p.glob("*.py"))
    }
    found.add("embodichain_core")
    missing = sorted(found - listed)
    assert not missing, f"add {missing} to [tool.setuptools] packages in pyproject.toml"


def test_wheel_carries_every_template_file(tmp_path: Path) -> None:
    build = tmp_path / "src"  # a copy: building in the checkout would leave build/ behind
    skip = shutil.ignore_patterns("__pycache__", "*.egg-info")
    for item in ("embodichain_core", "templates"):
        shutil.copytree(REPO / item, build / item, ignore=skip)
    for item in ("pyproject.toml", "README.md"):
        shutil.copy(REPO / item, build / item)
    run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "-q",
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(tmp_path / "dist"),
            str(build),
        ]
    )
    import zipfile

    wheel = next((tmp_path / "dist").glob("embodichain_core-*.whl"))
    shipped = {n for n in zipfile.ZipFile(wheel).namelist() if n.startswith("embodichain_core/templates/")}
    expected = {
        "embodichain_core/templates/" + p.relative_to(REPO / "templates").as_posix()
        for p in (REPO / "templates").rglob("*")
        if p.is_file() and "__pycache__" not in p.parts
    }
    assert expected <= shipped, sorted(expected - shipped)
    # installed from the wheel (ahead of the editable checkout on sys.path), `new` bakes from it
    target = tmp_path / "site"
    run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(target), str(wheel)])
    code = (
        "import sys, embodichain_core.templates as t\n"
        f"assert t.__file__.startswith({str(target)!r}), t.__file__\n"
        "from embodichain_core.cli.new_cmd import main\n"
        "sys.exit(main(['functor', 'from_wheel', '--no-input', '-o', 'out']))\n"
    )
    run([sys.executable, "-c", code], cwd=tmp_path, PYTHONPATH=str(target))
    assert (tmp_path / "out" / "embodichain-from-wheel" / "embodichain_from_wheel" / "functors.py").is_file()


# -- bake, install, test, discover -----------------------------------------------------------


def test_task_template_bakes_installs_tests_and_gym_makes(tmp_path: Path) -> None:
    assert new("task", TASK_NAME, "--no-input", "-o", str(tmp_path), "--max-episode-steps", "40") == 0
    package = tmp_path / TASK_DIST
    with installed(tmp_path / "site", package) as env:
        run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(package / "tests")], cwd=package, **env
        )
        code = (
            "import sys, gymnasium as gym, torch\n"
            "import embodichain_core\n"
            "from embodichain_core.cli.list_cmd import collect\n"
            f"assert {TASK_ID!r} in gym.registry, 'not discovered'\n"
            "assert 'embodichain_tmpl_reach.task' not in sys.modules, 'task module imported eagerly'\n"
            f"row = next(r for r in collect('tasks') if r['name'] == {TASK_ID!r})\n"
            f"env = gym.make({TASK_ID!r}, num_envs=2, verbose=False)\n"
            "obs, info = env.reset(seed=0)\n"
            "obs, reward, terminated, truncated, info = env.step(torch.zeros(2, 3))\n"
            "print(row['provider'], type(env).__name__, env.max_episode_steps, tuple(reward.shape),\n"
            "      tuple(obs['object']['cube_pos'].shape))\n"
        )
        out = run([sys.executable, "-c", code], cwd=tmp_path, **env)
        assert out.stdout.split() == [TASK_DIST, "TmplReachEnv", "40", "(2,)", "(2,", "3)"]
        cheap = (
            "import sys, embodichain_tmpl_reach.plugin\n"
            "heavy = {'torch', 'mujoco', 'embodichain_tmpl_reach.task'} & set(sys.modules)\n"
            "assert not heavy, f'the plugin module imports {heavy}'\n"
        )
        run([sys.executable, "-c", cheap], cwd=tmp_path, EMBODICHAIN_BLOCK_PLUGINS="*", **env)


def bake_functor(kind: str, output_dir: Path) -> Path:
    """Bake ``tmpl_<kind>`` of ``kind`` with ``embodichain new``; returns the package directory."""
    assert new("functor", f"tmpl_{kind}", "--kind", kind, "--no-input", "-o", str(output_dir)) == 0
    return next(output_dir.glob(f"embodichain-*tmpl-{kind}"))


def test_functor_template_bakes_installs_tests_and_registers(tmp_path: Path) -> None:
    package = bake_functor("randomization", tmp_path)
    assert package.name == "embodichain-randomize-tmpl-randomization"
    with installed(tmp_path / "site", package) as env:
        run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(package / "tests")], cwd=package, **env
        )
        code = (
            "import sys\n"
            "from embodichain_core.plugins import functor_registry\n"
            "entry = functor_registry().entry('randomize_tmpl_randomization')\n"
            "assert 'embodichain_randomize_tmpl_randomization.functors' not in sys.modules\n"
            "assert callable(entry.resolve())\n"
            "print(entry.meta['kind'], entry.meta['category'], entry.provider)\n"
        )
        out = run([sys.executable, "-c", code], cwd=tmp_path, **env).stdout.split()
    assert out == ["event", "randomization.physics", "embodichain-randomize-tmpl-randomization"]


def test_functor_template_every_kind_passes_its_tests(tmp_path: Path) -> None:
    """The other kinds' baked tests, importing the packages from their directories."""
    packages = [bake_functor(kind, tmp_path) for kind in FUNCTOR_KINDS if kind != "randomization"]
    run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "--import-mode=importlib",
            *[str(p / "tests") for p in packages],
        ],
        cwd=tmp_path,
        PYTHONPATH=os.pathsep.join(map(str, packages)),
    )
