"""Base of the class functors of this package: params checked when the manager builds them."""

from __future__ import annotations

from typing import Any

from embodichain_core.managers.functor import Functor

from embodichain_functors._common import ParamError


class CheckedFunctor(Functor):
    """A :class:`Functor` whose :meth:`check` validates ``cfg.params`` at construction.

    A bad param raises ``ValueError("params.<param>: ...")``, which the manager
    turns into a ``ConfigError`` at the functor's config path
    (``env.events.<name>: building functor <class> failed: params.<param>: ...``).
    """

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        try:
            self.check(env, **cfg.params)
        except ParamError as err:
            reason = err.reason.split(": ", 1)[-1]
            raise ValueError(f"params.{err.param}: {reason}") from None

    def check(self, *args: Any, **params: Any) -> None:
        """Validate the params (raise :class:`ParamError`); called once by ``__init__`` as
        ``check(env, **cfg.params)``."""
