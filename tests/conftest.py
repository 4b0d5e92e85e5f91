"""Shared fixtures: composing configs without a Hydra app, and a throw-away results folder."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra

from magexp.paths import CONF


@pytest.fixture
def make_cfg():
    """``make_cfg(*overrides)`` -> the composed run config."""

    def _make(*overrides):
        GlobalHydra.instance().clear()
        with initialize_config_dir(config_dir=str(CONF), version_base=None):
            return compose("config", overrides=list(overrides))

    return _make


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path, monkeypatch):
    """Each test gets its own run cache, so nothing is read from or left in .cache/."""
    monkeypatch.setattr("magexp.paths.CACHE", tmp_path / "cache")
    monkeypatch.setattr("magexp.cache.CACHE", tmp_path / "cache")
