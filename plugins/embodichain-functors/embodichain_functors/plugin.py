"""Registrations of embodichain-functors (entry point ``embodichain``): lazy
``"module:attr"`` strings only, so loading the plugin imports no functor module."""

from __future__ import annotations

from embodichain_core.plugins import FunctorRegister, hookimpl

from embodichain_functors.catalogue import FUNCTORS


@hookimpl
def embodichain_register_functors(register: FunctorRegister) -> None:
    """Register every standard functor (see :data:`embodichain_functors.catalogue.FUNCTORS`)."""
    for name, target, kind, category, description in FUNCTORS:
        register(name, target, kind=kind, category=category, description=description)
