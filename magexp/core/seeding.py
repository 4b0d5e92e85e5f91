"""Every random draw of a run derives from its seed and its scenario."""

from __future__ import annotations

import json
import zlib

import numpy as np
from omegaconf import DictConfig, OmegaConf

from magexp.errors import MagexpError


def stream_key(stream) -> int:
    """A stable 32-bit key of a scenario: CRC-32 of its name, or of its whole config (a mapping,
    as JSON with sorted keys).
    """
    text = json.dumps(stream, sort_keys=True, default=str) if isinstance(stream, dict) else str(stream)
    return zlib.crc32(text.encode())


def scenario_stream(scenario_cfg) -> dict:
    """The stream of a run: its scenario's whole resolved config (name and settings), so two
    scenarios, or one scenario at two settings (e.g. two noise levels), never share their draws.
    """
    if isinstance(scenario_cfg, DictConfig):
        return OmegaConf.to_container(scenario_cfg, resolve=True)
    return dict(scenario_cfg)


def run_generators(seed, stream=None) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent generators for the data and for the estimator of run ``seed``.

    ``stream`` names the scenario (:func:`scenario_stream`): ``SeedSequence(seed, spawn_key=(crc32(stream),))``,
    so two scenarios never share their draws (a lucky draw does not repeat across cases), while every
    estimator of a (scenario, seed) sees the same readings (common random numbers: paired
    comparisons). ``stream=None`` is the scenario-free sequence of ``seed``.
    """
    data, est = run_sequences(seed, stream)
    return np.random.default_rng(data), np.random.default_rng(est)


def run_sequences(seed, stream=None) -> tuple[np.random.SeedSequence, np.random.SeedSequence]:
    """The seed sequences behind :func:`run_generators` (data, estimator). ``default_rng`` of a
    sequence does not change it, so a batch derives them once per (scenario, seed) and gives each
    estimator a fresh generator with the same draws.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise MagexpError(f"seed={seed!r} is not allowed: it must be an integer >= 0")
    key = () if stream is None else (stream_key(stream),)
    data, est = np.random.SeedSequence(seed, spawn_key=key).spawn(2)
    return data, est
