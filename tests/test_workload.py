"""The replayed workload of issue 13.4: the committed list of the runs of ``make reproduce`` at
b533850, its mapping onto today's configs, and the replay through today's executor."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest
from omegaconf import OmegaConf

from magexp import workload
from magexp.config import compose_config, yaml_value
from magexp.errors import MagexpError
from magexp.paths import ROOT

CELLS = workload.DEFAULT_LIST.with_name("workload_b533850_cells.json")


@pytest.fixture(scope="module")
def rows():
    return workload.read_list(workload.DEFAULT_LIST)


@pytest.fixture(scope="module")
def cells():
    return {c["cell"]: c for c in json.loads(CELLS.read_text())}


def test_the_list_is_the_old_reproduce(rows):
    """2,952 distinct runs, 4,988 requested (the figures issue 13 measured at b533850), each once."""
    assert [r["run"] for r in rows] == list(range(len(rows)))
    assert len(rows) == 2952
    assert sum(r["requested"] for r in rows) == 4988
    assert len({(r["overrides"], r["seed"]) for r in rows}) == len(rows)
    for r in rows:
        assert r["artifact"] == r["artifacts"].split("|")[0]
        assert r["requested"] >= len(r["artifacts"].split("|"))
        old = workload.split(r["overrides"])
        if not any(o.startswith("estimator=kf_be") for o in old):  # those name today's field_kalman step
            assert workload.split(r["mapped"])[: len(old)] == old  # the old overrides, then the old defaults


def test_every_old_run_is_expressible(rows):
    statuses = Counter(r["status"] for r in rows)
    assert statuses == {"ok": 2952}, statuses


def _sample(cells, rows, n=12):
    """One cell per estimator of the list, and ``n`` more of its cells drawn with a fixed seed (a cell
    whose every run repeats another artifact's has no row of its own)."""
    by_estimator = {}
    for r in rows:
        name = dict(o.split("=", 1) for o in workload.split(r["overrides"]) if "=" in o).get("estimator")
        by_estimator.setdefault(name, r["cell"])
    rng = np.random.default_rng(13)
    drawn = rng.choice(sorted({r["cell"] for r in rows}), size=n, replace=False)
    return sorted(set(by_estimator.values()) | {int(c) for c in drawn})


def test_a_sample_maps_as_committed_and_composes_to_the_old_settings(cells, rows):
    """The committed mapping is what :func:`workload.map_cell` gives today, and today's config of
    the mapped overrides has the old value of every setting both versions have."""
    committed = {r["cell"]: (r["mapped"], r["status"]) for r in rows}
    for ci in _sample(cells, rows):
        cell = cells[ci]
        mapped, status = workload.map_cell(list(cell["overrides"]), cell["config"])
        assert (";".join(mapped), status) == committed[ci]
        _, old = workload.translate(list(cell["overrides"]), cell["config"])
        today = workload._leaves(workload._run_part(OmegaConf.to_container(compose_config(mapped), resolve=True)))
        for key, value in workload._leaves(workload._run_part(old)).items():
            assert today[key] == value, (ci, key)


def test_a_changed_default_becomes_an_override():
    """An old run whose setting differs from today's default keeps its old value."""
    old = OmegaConf.to_container(compose_config(["scenario=ding2024_exp1", "estimator=lm"]), resolve=True)
    old["estimator"]["tol"] = 1e-15
    mapped, status = workload.map_cell(["scenario=ding2024_exp1", "estimator=lm"], old)
    assert status == "ok"
    assert mapped == ["scenario=ding2024_exp1", "estimator=lm", "estimator.tol=1e-15"]


def test_a_new_setting_keeps_the_old_behaviour(monkeypatch):
    """A key the old code lacked is set to the value that does what the old code did."""
    old = OmegaConf.to_container(compose_config(["scenario=ding2024_exp1", "estimator=lm"]), resolve=True)
    del old["estimator"]["max_nfev"]
    mapped, status = workload.map_cell(["scenario=ding2024_exp1", "estimator=lm"], old)
    assert (mapped, status) == (["scenario=ding2024_exp1", "estimator=lm"], "ok")  # today's default
    monkeypatch.setitem(workload.OLD_BEHAVIOUR, "estimator.max_nfev", 5)
    mapped, status = workload.map_cell(["scenario=ding2024_exp1", "estimator=lm"], old)
    assert (mapped, status) == (["scenario=ding2024_exp1", "estimator=lm", "estimator.max_nfev=5"], "ok")


def test_a_removed_setting_is_inexpressible():
    old = OmegaConf.to_container(compose_config(["scenario=ding2024_exp1", "estimator=lm"]), resolve=True)
    old["estimator"]["warp"] = 3
    mapped, status = workload.map_cell(["scenario=ding2024_exp1", "estimator=lm"], old)
    assert status == "inexpressible: estimator.warp=3 has no key today"
    _, status = workload.map_cell(["scenario=ding2024_exp1", "estimator=kf_be_gone"], old)
    assert status.startswith("inexpressible: ") and "kf_be_gone" in status


def test_translate_puts_old_forms_in_todays_vocabulary():
    constant = {"_target_": "magexp.estimators.schedules.Constant", "value": 1.5}
    old = {"estimator": {"name": "kf_be", "p0": 1e10, "magnetization": {"name": "kf", "c1": constant}}}
    overrides, new = workload.translate(["scenario=yan2022_mockup", "estimator=kf_be"], old)
    assert overrides == ["scenario=yan2022_mockup", "estimator=kf", "+analysis=field_kalman"]
    assert new["estimator"] == {"name": "kf", "c1": {"_target_": "magexp.estimators.schedules.Linear",
                                                     "start": 1.5, "end": 1.5}}
    assert new["analysis"] == {"name": "field_kalman", "p0": 1e10}


@pytest.mark.parametrize("value", [None, True, 3, 1e-15, 0.7298, "clip", "a b'c", [0.5, 1.5], [[1, 0], [0, 1]]])
def test_override_values_parse_back(value):
    assert yaml_value(workload.override_value(value)) == value


def test_a_tiny_replay_runs_from_an_empty_cache(rows, tmp_path):
    """Three closed-form rows through today's run_many: computed (not cached), fits timed, and
    nothing left in the test's run cache or the temporary one."""
    from magexp import paths

    picked = [next(r for r in rows if f"estimator={name}" in r["mapped"].split(";")) for name in ("ellipsoid", "ls", "lm")]
    measured = workload.replay(picked, jobs=1)
    assert measured["runs"] == measured["computed"] == 3
    assert 0 < measured["fit_cpu_s"] <= measured["cpu_s"]
    assert measured["wall_s"] >= measured["plan_s"] > 0
    assert measured["outside_fit_ms_per_run"] == pytest.approx(
        (measured["cpu_s"] - measured["fit_cpu_s"]) / 3 * 1e3)
    assert not paths.CACHE.exists()  # the test's own cache was never written
    assert "inexpressible" not in workload.line(measured)


def test_replay_skips_inexpressible_rows(rows):
    row = dict(rows[0], status="inexpressible: gone")
    assert workload.configs_of([row]) == []


@pytest.mark.parametrize("edit, message", [
    (lambda text: text.replace("status", "state", 1), "column 'status' is missing"),
    (lambda text: text.replace(",ok\n", ",fine\n", 1), "status='fine' is not allowed"),
    (lambda text: text.replace("\n0,", "\nzero,", 1), "run='zero' is not an integer"),
])
def test_bad_lists_fail_in_one_line(tmp_path, edit, message):
    head = "".join(workload.DEFAULT_LIST.read_text().splitlines(keepends=True)[:3])
    bad = tmp_path / "bad.csv"
    bad.write_text(edit(head))
    with pytest.raises(MagexpError, match=message.replace("(", r"\(")):
        workload.read_list(bad)


def test_cli_bad_input_is_one_line(tmp_path, capsys):
    assert workload.main(["replay", str(tmp_path / "none.csv")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: workload list") and err.count("\n") == 1
    assert workload.main(["replay", "--limit", "0"]) == 2
    assert "--limit 0" in capsys.readouterr().err
    assert workload.main(["replay", "--every", "-1"]) == 2
    assert "--every -1 is not allowed" in capsys.readouterr().err


def test_the_old_side_refuses_todays_code(tmp_path):
    """tools/old_workload.py runs only against the b533850 checkout."""
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "old_workload.py"), "list", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode != 0 and "b533850" in done.stderr
    assert not list(tmp_path.iterdir())


def test_pick_samples_whole_cells(rows):
    mixed = [dict(r, status="inexpressible: x") if r["run"] % 3 == 0 else r for r in rows]
    picked = workload.pick(mixed, every=4)
    assert picked and all(r["cell"] % 4 == 0 and r["status"] == "ok" for r in picked)
    assert len(picked) == sum(r["cell"] % 4 == 0 and r["run"] % 3 != 0 for r in rows)
    assert len({r["cell"] for r in picked}) > 20
    assert workload.pick(mixed, every=4, limit=5) == picked[:5]


def test_measurement_lines_parse_back():
    measured = {"side": "after", "runs": 3, "wall_s": 1.5, "outside_fit_ms_per_run": 2.25}
    assert workload.parse_line("noise\n" + workload.line(measured) + " inexpressible=0\n") == {
        "side": "after", "runs": 3.0, "wall_s": 1.5, "outside_fit_ms_per_run": 2.25, "inexpressible": 0.0}
    with pytest.raises(MagexpError, match="no measurement line"):
        workload.parse_line("Traceback ...")


def test_compare_needs_an_old_checkout(tmp_path):
    with pytest.raises(MagexpError, match="a b533850 checkout with its .venv"):
        workload.compare(tmp_path, jobs=1, rounds=1)
    fake = tmp_path / ".venv" / "bin"
    fake.mkdir(parents=True)
    (fake / "python").symlink_to(sys.executable)  # today's interpreter: the old side's tool refuses it
    with pytest.raises(MagexpError, match="the before replay failed"):
        workload.compare(tmp_path, jobs=1, rounds=1, every=1000)
