"""The one-line errors of an override the composed config refuses: a key it does not have (with the keys that
exist beside it), or a value its schema's type refuses (with the type wanted)."""

from __future__ import annotations

from omegaconf import DictConfig

from magexp.errors import MagexpError

PRIMARY = "config"
#: keys that belonged to the simulation command before calibration got its own
CALIBRATE_KEYS = ("task", "data", "out")


def _keys_of(cfg: DictConfig, key: str) -> tuple[str, list[str]]:
    """The deepest existing parent of dotted ``key`` and its keys."""
    parts = key.split(".")
    node, path = cfg, []
    for part in parts[:-1]:
        child = node.get(part) if isinstance(node, DictConfig) else None
        if not isinstance(child, DictConfig):
            break
        node, path = child, path + [part]
    return ".".join(path) or "the config", sorted(str(k) for k in node.keys()) if isinstance(node, DictConfig) else []


def unknown_key(cfg: DictConfig, key: str, value: str, config_name: str = PRIMARY) -> MagexpError:
    """The one-line error of an override whose key is not in the config."""
    if config_name == PRIMARY and key.split(".")[0] in CALIBRATE_KEYS:
        return MagexpError(f"{key}={value} is not allowed: the simulation command has no {key.split('.')[0]!r}; "
                           "calibrate a recording with `magexp calibrate data.path=<file> ...`")
    where, keys = _keys_of(cfg, key)
    return MagexpError(f"{key}={value} is not allowed: {where} has no key {key.split('.')[-1]!r} "
                       f"(keys: {', '.join(keys)})")


def bad_value(key: str, value: str, exc: BaseException) -> MagexpError:
    """A value the schema's type refuses: one line naming the key, the value and the type wanted."""
    while exc.__cause__ is not None:  # Hydra keeps OmegaConf's reason in the cause
        exc = exc.__cause__
    msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    for name, wanted in (("Integer", "an integer"), ("Float", "a number"), ("Boolean", "true or false")):
        if f"converted to {name}" in msg:
            return MagexpError(f"{key}={value} is not allowed: it must be {wanted}")
    return MagexpError(f"{key}={value} is not allowed: {msg}")
