"""mypy plugin: the methods ``@configclass`` adds at decoration time, declared to mypy.

:pep:`681` (``dataclass_transform`` on :func:`~embodichain_core.utils.configclass.configclass`)
tells type checkers about the fields and the generated ``__init__``; it cannot declare
methods. This plugin adds, to every decorated class, the signatures of ``to_dict``,
``from_dict``, ``replace``, ``copy`` and ``validate`` (plus the ``from_dict`` hooks),
returning the decorated class itself, exactly where the decorator attaches them at
run time: not where the class or a non-config base defines the method.

Enable it in the project's mypy configuration (the core's pyproject.toml does)::

    [tool.mypy]
    plugins = ["embodichain_core.utils.mypy_plugin"]

The module imports mypy, so only mypy loads it.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

from mypy.nodes import ARG_OPT, ARG_POS, ARG_STAR2, ArgKind, Argument, TypeInfo, Var
from mypy.plugin import ClassDefContext, Plugin
from mypy.plugins.common import add_method_to_class
from mypy.plugins.dataclasses import dataclass_class_maker_callback
from mypy.types import AnyType, Instance, TupleType, Type, TypeOfAny, TypeType
from mypy.typevars import fill_typevars

CONFIGCLASS = "embodichain_core.utils.configclass.configclass"


class _Method(NamedTuple):
    args: list[Argument]
    returns: Type
    is_classmethod: bool = False


def _arg(name: str, typ: Type, kind: ArgKind = ARG_POS) -> Argument:
    return Argument(Var(name, typ), typ, None, kind)


def _methods(ctx: ClassDefContext) -> dict[str, _Method]:
    """Name -> signature of each method the decorator attaches (configclass._METHODS)."""
    api = ctx.api
    own: Instance | TupleType = fill_typevars(ctx.cls.info)
    any_t = AnyType(TypeOfAny.explicit)
    str_t = api.named_type("builtins.str")
    data_t = api.named_type("builtins.dict", [any_t, any_t])
    path = _arg("path", str_t)
    return {
        "to_dict": _Method([], api.named_type("builtins.dict", [str_t, any_t])),
        "from_dict": _Method([_arg("data", any_t), _arg("path", str_t, ARG_OPT)], own, True),
        "_resolve_subclass": _Method([_arg("data", data_t), path], api.named_type("builtins.type"), True),
        "_build_from_dict": _Method([_arg("data", data_t), path], own, True),
        "replace": _Method([_arg("changes", any_t, ARG_STAR2)], own),
        "copy": _Method([], own),
        "validate": _Method([_arg("prefix", str_t, ARG_OPT)], api.named_type("builtins.list", [str_t])),
    }


def _defined_outside_configclass(info: TypeInfo, name: str) -> bool:
    """The class itself, or a base that is no config class, defines ``name``."""
    for klass in info.mro[:-1]:  # not object
        node = klass.names.get(name)
        if node is not None and not node.plugin_generated:
            return True
        if node is not None:  # added by this plugin to a config base: add again, typed for info
            return False
    return False


def _configclass_hook(ctx: ClassDefContext) -> bool:
    """The fields (mypy's dataclass_transform support, which a plugin hook replaces), then the methods."""
    if not dataclass_class_maker_callback(ctx):
        return False  # a base is not processed yet: mypy calls again
    _add_configclass_methods(ctx)
    return True


def _add_configclass_methods(ctx: ClassDefContext) -> None:
    info = ctx.cls.info
    for name, method in _methods(ctx).items():
        if _defined_outside_configclass(info, name):
            continue
        add_method_to_class(
            ctx.api,
            ctx.cls,
            name,
            method.args,
            method.returns,
            self_type=TypeType(fill_typevars(info)) if method.is_classmethod else None,
            is_classmethod=method.is_classmethod,
        )


class ConfigclassPlugin(Plugin):
    """Declares the ``@configclass`` methods on each decorated class."""

    def get_class_decorator_hook_2(self, fullname: str) -> Callable[[ClassDefContext], bool] | None:
        return _configclass_hook if fullname == CONFIGCLASS else None


def plugin(version: str) -> type[Plugin]:
    """mypy's entry point."""
    return ConfigclassPlugin
