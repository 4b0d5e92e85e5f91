"""experiments/real: skipped in one line per artifact without the recordings, run (tiny) with them."""

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


# real_modes run on the recordings (tiny): tests/test_artifacts.py::test_artifact_runs_tiny[real_modes]
