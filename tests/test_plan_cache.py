"""Plans read, not composed (:mod:`magexp.artifacts.plan_cache`; issue 42 item 7): a warm reproduction reads
each artifact's plan, the same runs to the type and key order; a changed input or a damaged entry composes it
again; run keys and run rows read from the cache are those of the whole path."""

from __future__ import annotations

import json

import numpy as np

from magexp import paths
from magexp.artifacts import plan as planning
from magexp.artifacts import plan_cache
from magexp.artifacts.spec import load
from magexp.run import cache, runkeys
from magexp.run.executor import ROW_FIELDS, run_row
from magexp.estimators.result import RunOutput

SPEC = paths.EXPERIMENTS / "yan2022" / "yan2022_table_mockup.yaml"


def _counted(monkeypatch) -> list:
    """Each call of plan_artifact (the composing) recorded."""
    calls, real = [], planning.plan_artifact
    monkeypatch.setattr(planning, "plan_artifact", lambda *a, **k: calls.append(1) or real(*a, **k))
    return calls


def _same(a, b) -> bool:
    return json.dumps([a.cells, a.overrides, [list(i) for i in a.index], a.configs]) == \
        json.dumps([b.cells, b.overrides, [list(i) for i in b.index], b.configs]) and a.index == b.index


def test_a_plan_is_composed_once_then_read_the_same(monkeypatch):
    calls = _counted(monkeypatch)
    spec = load(SPEC)
    first = plan_cache.planned(spec, seeds=2, tiny=True)
    again = plan_cache.planned(load(SPEC), seeds=2, tiny=True)
    assert len(calls) == 1 and _same(first, again) and len(again.configs) == 2 * len(again.cells)
    assert again.configs[1] == {**first.configs[1]} and again.configs[0]["seed"] == 0
    plan_cache.planned(spec, seeds=3, tiny=True)  # another plan: composed
    plan_cache.planned(spec, seeds=2, tiny=True, fresh=True)  # --force: composed again
    assert len(calls) == 3


def test_a_changed_input_or_a_damaged_entry_composes_again(monkeypatch, tmp_path):
    calls = _counted(monkeypatch)
    spec = load(SPEC)
    plan_cache.planned(spec, seeds=1, tiny=True)
    entry = plan_cache.entry(plan_cache.key(spec, 1, True))
    data = bytearray(entry.read_bytes())
    data[-2] ^= 1
    entry.write_bytes(bytes(data))
    assert _same(plan_cache.planned(spec, seeds=1, tiny=True), planning.plan_artifact(spec, seeds=1, tiny=True))
    assert len(calls) == 3  # the damaged entry was composed again (and the direct plan)
    edited = tmp_path / "conf"
    before = plan_cache.key(spec, 1, True)
    plan_cache.inputs_digest.cache_clear()
    monkeypatch.setattr(paths, "CONF", edited)
    edited.mkdir()
    (edited / "config.yaml").write_text("seed: 0\n")
    try:
        assert plan_cache.key(spec, 1, True) != before  # a config edit is another plan
    finally:
        plan_cache.inputs_digest.cache_clear()


def test_run_keys_are_each_configs_run_key():
    shared = {"_target_": "magexp.scenarios.ding.DingScenario", "noise": 2.0, "box": [1, [2, 3]], "s": "é"}
    configs = [{"scenario": shared, "estimator": {"_target_": "x.Y", "n": 3}, "seed": seed} for seed in range(3)]
    configs.append({"seed": 1, "estimator": {"n": 1.0}, "scenario": dict(shared, noise=None)})
    assert runkeys.run_keys(configs) == [runkeys.run_key(c) for c in configs]
    assert len(set(runkeys.run_keys(configs))) == 4


def test_a_row_read_from_its_fields_is_the_row_of_the_whole_run(tmp_path):
    out = RunOutput(metrics={"fun": 1.5, "nit": 3, "list": [1, 2]}, history=np.arange(4.0),
                    history_nfev=np.arange(4), x=np.array([0.5, -1.0]), parameter_names=["a", "b"])
    assert cache.store("k" * 32, out, tmp_path)
    whole, part = cache.load("k" * 32, tmp_path), cache.load("k" * 32, tmp_path, fields=ROW_FIELDS)
    assert json.dumps(run_row(whole)) == json.dumps(run_row(part)) and not hasattr(part, "history")
    path = cache.entry_path("k" * 32, tmp_path)
    path.write_bytes(path.read_bytes().replace(b'"nit": 3', b'"nit": 4'))  # content no longer matches its digest
    assert cache.load("k" * 32, tmp_path, fields=ROW_FIELDS) is None
    assert any("not valid" in line for line in cache.say_notes())


def test_rows_kept_beside_their_entries_are_the_rows_read_and_a_replaced_entry_is_read_again(tmp_path, monkeypatch):
    from magexp.run import executor

    outs = {f"{c}{'0' * 31}": RunOutput(metrics={"fun": 0.1 * i, "nan": float("nan"), "ok": True, "n": i},
                                         history=np.zeros(2), history_nfev=np.zeros(2, int), x=np.array([i, -0.0]),
                                         parameter_names=["a", "b"]) for i, c in enumerate("ab")}
    for key, out in outs.items():
        assert cache.store(key, out)
    first = {key: i for i, key in enumerate(outs)}
    read = executor.cached_rows(first, True)
    assert set(cache.known_rows(first)) == set(outs)  # kept beside the entries
    loads = []
    real = cache.load
    monkeypatch.setattr(cache, "load", lambda *a, **k: loads.append(a[0]) or real(*a, **k))
    again = executor.cached_rows(first, True)
    assert loads == [] and json.dumps(again) == json.dumps(read)  # no entry read, the same rows to the byte
    key = next(iter(outs))
    changed = RunOutput(**{**vars(outs[key]), "metrics": {"fun": 9.0}})
    assert cache.store(key, changed)  # a new file: its stamp differs
    rows = executor.cached_rows(first, True)
    assert loads == [key] and rows[key]["fun"] == 9.0
