"""``@configclass`` under mypy: fields through ``dataclass_transform``, ``MISSING`` fits any
annotation, and the plugin ``embodichain_core/utils/mypy_plugin.py`` declares the methods
the decorator adds, each returning the decorated class."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

from mypy import api

import embodichain_core
from embodichain_core.utils.configclass import MISSING

PACKAGE = Path(embodichain_core.__file__).resolve().parent

SNIPPET = """
from embodichain_core.utils.configclass import MISSING, configclass


@configclass
class ArmCfg:
    uid: str = MISSING
    init_pos: tuple = (0.0, 0.0, 0.0)


@configclass
class RobotCfg(ArmCfg):
    dof: int = 7

    def validate(self, prefix: str = "", *, strict: bool = True) -> list[str]:
        return super().validate(prefix)


arm = ArmCfg.from_dict({"uid": "arm"})
reveal_type(arm)
reveal_type(RobotCfg.from_dict({}, "robot"))
reveal_type(arm.replace(uid="b"))
reveal_type(RobotCfg(uid="r", dof=6).copy())
reveal_type(arm.to_dict())
reveal_type(arm.validate())
ArmCfg(uid=1)
ArmCfg(size=2)
"""


def _mypy(tmp_path: Path, source: str) -> list[str]:
    (tmp_path / "snippet.py").write_text(source)
    (tmp_path / "mypy.ini").write_text(
        "[mypy]\npython_version = 3.10\nignore_missing_imports = True\nfollow_imports = silent\n"
        f"mypy_path = {PACKAGE.parent}\nplugins = {PACKAGE / 'utils' / 'mypy_plugin.py'}\n"
    )
    out, err, _ = api.run(
        [
            "--config-file",
            str(tmp_path / "mypy.ini"),
            "--cache-dir",
            str(tmp_path / "cache"),
            "--no-error-summary",
            "--hide-error-context",
            str(tmp_path / "snippet.py"),
        ]
    )
    assert not err, err
    return [re.sub(r"^.*snippet\.py:\d+: ", "", line) for line in out.splitlines()]


def test_mypy_sees_fields_and_the_added_methods(tmp_path: Path) -> None:
    lines = _mypy(tmp_path, SNIPPET)
    assert lines == [
        'note: Revealed type is "snippet.ArmCfg"',
        'note: Revealed type is "snippet.RobotCfg"',
        'note: Revealed type is "snippet.ArmCfg"',
        'note: Revealed type is "snippet.RobotCfg"',
        'note: Revealed type is "dict[str, Any]"',
        'note: Revealed type is "list[str]"',
        'error: Argument "uid" to "ArmCfg" has incompatible type "int"; expected "str"  [arg-type]',
        'error: Unexpected keyword argument "size" for "ArmCfg"  [call-arg]',
    ]


def test_missing_is_the_dataclasses_sentinel() -> None:
    assert MISSING is dataclasses.MISSING
