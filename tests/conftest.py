"""Shared fixtures: composing configs through the one composer, and a throw-away run cache."""

from __future__ import annotations

import pytest

from magexp.config import compose_config


@pytest.fixture
def make_cfg():
    """``make_cfg(*overrides)`` -> the composed run config (:func:`magexp.config.compose_config`)."""

    def _make(*overrides):
        return compose_config(list(overrides))

    return _make


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path, monkeypatch):
    """Each test gets its own run cache, so nothing is read from or left in .cache/."""
    monkeypatch.setattr("magexp.paths.CACHE", tmp_path / "cache")
    monkeypatch.setattr("magexp.cache.CACHE", tmp_path / "cache")


def _missing_recording(value) -> str | None:
    """The recording a parametrised scenario or artifact reads, when it is absent from
    :data:`magexp.paths.SHARED_DATA` (the recordings of others are never shipped), else None."""
    import yaml

    from magexp.paths import CONF, EXPERIMENTS, SHARED_DATA

    from pathlib import Path

    if isinstance(value, Path) and value.suffix == ".yaml":  # an artifact file
        value = value.stem
    if not isinstance(value, str):
        return None
    scenario = CONF / "scenario" / f"{value}.yaml"
    if scenario.is_file():
        name = (yaml.safe_load(scenario.read_text()) or {}).get("file")
        files = [] if not name else [name] if "." in name else [f"{name}_mag.csv"]
    else:
        artifacts = list(EXPERIMENTS.glob(f"*/{value}.yaml"))
        files = (yaml.safe_load(artifacts[0].read_text()) or {}).get("requires_data") or [] if artifacts else []
    return next((f for f in files if not (SHARED_DATA / f).is_file()), None)


def pytest_collection_modifyitems(config, items):
    """Tests parametrised over a recorded scenario or artifact skip cleanly without the recordings."""
    for item in items:
        params = getattr(getattr(item, "callspec", None), "params", {})
        for value in params.values():
            missing = _missing_recording(value)
            if missing:
                item.add_marker(pytest.mark.skip(reason=f"{missing} is not in the recordings folder (MAGEXP_DATA)"))
                break
