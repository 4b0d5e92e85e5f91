"""Pre-flight checks of command-line overrides, so that a bad value is one line, not a traceback."""

from __future__ import annotations

import itertools
from pathlib import Path

from magexp.errors import MagexpError
from magexp.paths import CONF

GROUPS = ("scenario", "estimator")


def options(group: str) -> list[str]:
    """Config names available in ``conf/<group>/``."""
    return sorted(p.stem for p in (CONF / group).glob("*.yaml"))


def target_class(group: str, name: str):
    """The class named by ``_target_`` in ``conf/<group>/<name>.yaml`` (imported, not built)."""
    import importlib

    from omegaconf import OmegaConf

    module, _, cls = str(OmegaConf.load(CONF / group / f"{name}.yaml")["_target_"]).rpartition(".")
    return getattr(importlib.import_module(module), cls)


def _choices(overrides: list[str]) -> list[list[str]]:
    """Each override expanded into its sweep values (a plain override is a sweep of one)."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    parser = OverridesParser.create()
    try:
        parsed = parser.parse_overrides(overrides)
    except Exception as exc:
        raise MagexpError(f"could not parse the overrides: {str(exc).splitlines()[0]}") from None
    expanded = []
    for ov in parsed:
        key = ov.get_key_element()
        if ov.is_sweep_override():
            values = [str(v) for v in ov.sweep_string_iterator()]
        else:
            values = [ov.get_value_element_as_str()]
        expanded.append([f"{key}={v}" for v in values])
    return expanded


def check_overrides(overrides: list[str]) -> None:
    """Compose the config for every value of every override; raise a one-line MagexpError."""
    from hydra import compose, initialize_config_dir

    user = [o for o in overrides if not o.lstrip("+~").startswith("hydra")]
    for ov in user:
        key, _, value = ov.partition("=")
        if key in GROUPS:
            for v in value.split(","):
                if v and v not in options(key):
                    raise MagexpError(f"{key}={v!r} is not allowed: choose one of {', '.join(options(key))}")
    expanded = _choices(user)
    base = [vals[0] for vals in expanded]
    with initialize_config_dir(config_dir=str(CONF), version_base=None):
        trials = [base] + [base[:i] + [v] + base[i + 1:] for i, vals in enumerate(expanded) for v in vals[1:]]
        for trial in itertools.islice(trials, 200):
            try:
                compose("config", overrides=trial)
            except Exception as exc:
                lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
                detail = "; ".join([lines[0]] + [ln for ln in lines[1:] if "not in struct" in ln or "Error" in ln][:1])
                raise MagexpError(f"bad override: {detail}") from None
