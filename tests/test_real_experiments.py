"""experiments/real: skipped in one line per artifact without the recordings, run (tiny) with them."""

import pandas as pd
import pytest

from magexp import paths
from magexp.artifacts.plan import paper_specs


def test_every_real_artifact_names_the_recordings_it_needs():
    specs = paper_specs("real")
    assert {s.name for s in specs} == {"real_benchmark", "real_modes", "real_table7"}
    assert all(s.get("requires_data") for s in specs)


def test_absent_recordings_skip_each_artifact_in_one_line(tmp_path, monkeypatch):
    from magexp.artifacts.reproduce import reproduce_paper

    monkeypatch.setattr(paths, "SHARED_DATA", tmp_path / "nothing")
    lines = []
    summary = reproduce_paper("real", root=tmp_path / "res", seeds=1, jobs=1, tiny=True, log=lines.append)
    assert len(lines) == 3 and all("skipped" in ln and "MAGEXP_DATA" in ln for ln in lines), lines
    assert summary.empty and not list((tmp_path / "res" / "real").glob("*.png"))


@pytest.mark.skipif(not (paths.SHARED_DATA / "hmc5883l_rotate-ccw-around-z_mag.csv").is_file(), reason="recordings absent")
@pytest.mark.slow
def test_modes_artifact_runs_on_the_recordings(tmp_path):
    from magexp.artifacts.reproduce import reproduce_paper

    summary = reproduce_paper("real", root=tmp_path, seeds=1, jobs=1, tiny=True, only="real_modes", force=True,
                              log=lambda *_: None)
    frac = summary[summary.quantity == "vector_residual_fraction"]
    assert len(frac) == 5 and (frac.value < 0.05).all()  # gyro and magnetometer agree to a few % of the field
    runs = pd.read_csv(tmp_path / "real" / "real_modes_runs.csv")
    assert runs.weakest_combination.notna().all()
