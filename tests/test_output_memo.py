"""Outputs memoised by their inputs (issue 42 item 7): a warm reproduction writes no unchanged artifact and
builds no unchanged report; a changed spec, run row or output file writes again, and ``--force`` always does."""

from __future__ import annotations

import dataclasses
import shutil

import pandas as pd
import pytest

from magexp.artifacts import artifact_memo, report_memo, reproduce
from magexp.artifacts.plan_cache import planned
from magexp.artifacts.spec import load
from magexp.artifacts.stored import summarise_stored
from magexp.paths import EXPERIMENTS
from magexp.run import cache
from magexp.run.executor import run_many

NAME = "yan2022_table_mockup"


@pytest.fixture
def warm(tmp_path, mockup_reproduction):
    """A copy of the mock-up reproduction's output folder, its runs in this test's run cache, and the
    artifact's plan and outputs (read from that cache)."""
    out = tmp_path / "res"
    shutil.copytree(mockup_reproduction.out, out)
    shutil.copytree(mockup_reproduction.runs, cache.CACHE)
    spec = load(EXPERIMENTS / "yan2022" / f"{NAME}.yaml")
    plan = planned(spec, seeds=2, tiny=True)
    return out, plan, run_many(plan.configs, jobs=1)


def _mtimes(out):
    return {p: p.stat().st_mtime_ns for p in artifact_memo.files(load(EXPERIMENTS / "yan2022" / f"{NAME}.yaml"),
                                                                   out / "yan2022")}


def _write(plan, outputs, out, **kw):
    return reproduce.write_unchanged(plan, outputs, out / "yan2022", seeds=2, tiny=True, **kw)


class _Edited:
    """The outputs of a plan with the first run's row changed."""

    def __init__(self, outputs):
        self.outputs, self.keys = outputs, outputs.keys

    def __len__(self):
        return len(self.outputs)

    def metrics(self, i):
        row = self.outputs.metrics(i)
        return {**row, "fit_rms": row["fit_rms"] * 2} if i == 0 else row

    def __getitem__(self, i):
        return self.outputs[i]


def test_an_unchanged_artifact_is_not_written_and_its_summary_rows_are_the_recomputed_ones(warm, mockup_reproduction):
    out, plan, outputs = warm
    first = _write(plan, outputs, out)  # an empty memo: written, the same bytes as the reproduction's
    assert all(p.read_bytes() == mockup_reproduction.files[p.relative_to(out).as_posix()] for p in _mtimes(out))
    before = _mtimes(out)
    again = _write(plan, outputs, out)
    assert _mtimes(out) == before  # not written again
    pd.testing.assert_frame_equal(again, first)
    pd.testing.assert_frame_equal(again, summarise_stored(plan.spec, out / "yan2022"))


#: make test: one input and one output changed; make test-full every case
@pytest.mark.parametrize("change", [pytest.param(c, marks=[] if c in ("run row", "deleted file") else [pytest.mark.full])
                                    for c in ("spec", "run row", "deleted file", "edited file", "force")])
def test_a_changed_input_or_output_writes_the_artifact_again(warm, mockup_reproduction, change, figures_not_rendered):
    out, plan, outputs = warm
    _write(plan, outputs, out)
    before = _mtimes(out)
    cells = out / "yan2022" / f"{NAME}_cells.csv"
    if change == "spec":
        plan = dataclasses.replace(plan, spec=dataclasses.replace(plan.spec, title=plan.spec.title + " (edited)"))
    elif change == "run row":
        outputs = _Edited(outputs)
    elif change == "deleted file":
        cells.unlink()
    elif change == "edited file":
        cells.write_text("edited by hand\n")
    rows = _write(plan, outputs, out, force=change == "force")
    assert all(_mtimes(out)[p] != before[p] for p in before if p.suffix == ".csv")  # written again
    if change in ("deleted file", "edited file", "force"):  # restored: the reproduction's bytes
        assert cells.read_bytes() == mockup_reproduction.files[f"yan2022/{cells.name}"]
    if change == "run row":
        runs = f"yan2022/{NAME}_runs.csv"
        assert (out / runs).read_bytes() != mockup_reproduction.files[runs]
    pd.testing.assert_frame_equal(rows, summarise_stored(plan.spec, out / "yan2022"))


def test_the_report_is_built_once_per_content_of_its_folder(warm, monkeypatch, mockup_reproduction):
    out, _, _ = warm
    builds = []
    real = report_memo.build
    monkeypatch.setattr(report_memo, "build", lambda root: builds.append(root) or real(root))
    assert report_memo.built(out) and len(builds) == 1  # an empty memo: built, the reproduction's bytes
    report = out / "REPORT.md"
    assert report.read_bytes() == mockup_reproduction.files["REPORT.md"]
    stamp = report.stat().st_mtime_ns
    assert not report_memo.built(out) and len(builds) == 1 and report.stat().st_mtime_ns == stamp  # unchanged: kept
    (out / "timing.csv").write_text("target,seconds\nall,1.0\n")  # written after the build, never read by it
    assert not report_memo.built(out) and len(builds) == 1

    versions = out / "versions.csv"  # rewritten when the record changes, without a build
    monkeypatch.setattr(report_memo, "versions", lambda: {"python": "0", "magexp_commit": "abc"})
    assert not report_memo.built(out) and len(builds) == 1
    assert versions.read_text() == "package,version\npython,0\nmagexp_commit,abc\n"

    summary = out / "yan2022" / "summary.csv"  # a CSV it reads, changed: built again
    summary.write_text(summary.read_text() + "\n")
    assert report_memo.built(out) and len(builds) == 2
    assert not report_memo.built(out) and len(builds) == 2
    (out / "APPENDIX.md").unlink()  # an output deleted: built again
    assert report_memo.built(out) and len(builds) == 3
    assert (out / "APPENDIX.md").read_bytes() == mockup_reproduction.files["APPENDIX.md"]
    assert report_memo.built(out, force=True) and len(builds) == 4  # --force builds it all the same


@pytest.mark.full  # make test's budget: a slow case (make test-full runs it)
def test_a_warm_reproduction_writes_nothing_and_gives_the_same_bytes(warm, monkeypatch, mockup_reproduction, capsys):
    out, _, _ = warm
    argv = [*mockup_reproduction.args, "--out", str(out)]
    assert reproduce.main(argv) == 0  # fills the memos
    kept = {p: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()}
    monkeypatch.setattr(reproduce, "write_artifact", lambda *a, **k: pytest.fail("an unchanged artifact was written"))
    monkeypatch.setattr(report_memo, "build", lambda *a: pytest.fail("an unchanged report was built"))
    assert reproduce.main(argv) == 0
    again = {p: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()}
    assert {p for p in kept if kept[p] != again[p]} <= {out / "yan2022" / "summary.csv", out / "timing.csv"}
    for rel, data in mockup_reproduction.files.items():
        if rel not in ("versions.csv", "timing.csv"):
            assert (out / rel).read_bytes() == data, rel
    assert "0 computed" in capsys.readouterr().out
