"""Configuration errors that carry the path inside the config."""

from __future__ import annotations

from typing import Iterable

from embodichain_core.utils.suggest import did_you_mean


class ConfigError(ValueError):
    """A configuration value is wrong.

    Attributes:
        path: dotted path of the offending entry inside the config
            (``env.events.randomize_light.params.entity_cfg.uid``), or ``""``.
        reason: the message without the path.
    """

    def __init__(self, path: str, reason: str):
        self.path = path
        self.reason = reason
        super().__init__(f"{path}: {reason}" if path else reason)

    def under(self, prefix: str) -> "ConfigError":
        """The same error with ``prefix`` prepended to its path."""
        path = f"{prefix}.{self.path}" if self.path else prefix
        err = ConfigError(path, self.reason)
        err.__cause__ = self.__cause__ or self
        return err


def join_path(*parts: object) -> str:
    """Join path components, skipping empty ones; ints become ``[i]``."""
    out = ""
    for part in parts:
        if part is None or part == "":
            continue
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out = f"{out}.{part}" if out else str(part)
    return out


def unknown_key(path: str, key: str, valid: Iterable[str], what: str = "key") -> ConfigError:
    """Error for an unknown key, suggesting the closest valid ones."""
    return ConfigError(join_path(path, key), f"unknown {what} {key!r}.{did_you_mean(key, valid)}")
