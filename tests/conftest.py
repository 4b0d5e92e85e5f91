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
