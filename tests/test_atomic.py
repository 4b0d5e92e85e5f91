"""Every output file written atomically (:mod:`magexp.core.atomic`): a write interrupted midway leaves the
previous file intact and no partial or temporary file."""

from __future__ import annotations

import os

import numpy as np
import pytest

from magexp.core.atomic import atomic_open, atomic_path, write_text


class Interrupted(Exception):
    pass


def test_an_interrupted_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    path = write_text(tmp_path / "table.csv", "old\n")
    with pytest.raises(Interrupted):
        with atomic_open(path, "w") as fh:
            fh.write("new, half-written")
            fh.flush()
            assert path.read_text() == "old\n"  # not visible before the write completes
            raise Interrupted
    assert path.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_a_new_file_appears_only_complete_with_the_usual_permissions(tmp_path):
    path = tmp_path / "new.txt"
    with pytest.raises(Interrupted):
        with atomic_path(path) as tmp:
            tmp.write_text("partial")
            raise Interrupted
    assert list(tmp_path.iterdir()) == []
    write_text(path, "whole\n")
    mask = os.umask(0)
    os.umask(mask)
    assert path.read_text() == "whole\n" and path.stat().st_mode & 0o777 == 0o666 & ~mask


def test_a_figure_killed_while_drawing_keeps_the_previous_one(tmp_path, monkeypatch):
    from magexp.artifacts.plots.style import plt, save

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    png, pdf = save(fig, tmp_path / "fig.png")
    old = png.read_bytes(), pdf.read_bytes()
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    original = type(fig).savefig

    def dies_in_the_pdf(self, target, **kwargs):  # the PNG is written, the PDF half-written
        original(self, target, **kwargs)
        if kwargs.get("format") == "pdf":
            raise Interrupted

    monkeypatch.setattr(type(fig), "savefig", dies_in_the_pdf)
    with pytest.raises(Interrupted):
        save(fig, tmp_path / "fig.png")
    assert pdf.read_bytes() == old[1]  # the PDF as it was, not a truncated one
    assert png.read_bytes() != old[0]  # the PNG was complete: it was replaced whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.pdf", "fig.png"]


def test_a_calibration_interrupted_while_writing_leaves_no_file(tmp_path, monkeypatch):
    import magexp.calibration.write as output
    from magexp import calibrate

    rng = np.random.default_rng(0)
    u = rng.normal(size=(200, 3))
    cal = calibrate(48 * u / np.linalg.norm(u, axis=1, keepdims=True) + [3, -2, 1], unit="uT", folds=0)
    original = output.write_readings

    def killed_midway(cal, fh):  # Ctrl-C while the table is being written
        original(cal, fh)
        fh.flush()
        raise KeyboardInterrupt

    monkeypatch.setattr(output, "write_readings", killed_midway)
    with pytest.raises(KeyboardInterrupt):
        output.write(cal, tmp_path / "deep" / "cal", seed=0)
    assert list(tmp_path.iterdir()) == []  # no truncated calibrated.csv, no JSON, not even the folders


def test_the_calibrated_table_is_written_in_blocks_as_one(tmp_path, monkeypatch):
    import io

    import magexp.calibration.write as output
    from magexp import calibrate

    rng = np.random.default_rng(1)
    u = rng.normal(size=(301, 3))
    cal = calibrate(48 * u / np.linalg.norm(u, axis=1, keepdims=True) + [3, -2, 1], unit="uT", folds=0)
    whole = io.StringIO()
    output.write_readings(cal, whole)
    monkeypatch.setattr(output, "ROWS_PER_BLOCK", 7)
    blocks = io.StringIO()
    output.write_readings(cal, blocks)
    assert blocks.getvalue() == whole.getvalue()
    lines = whole.getvalue().splitlines()
    assert len(lines) == 4 + 301
    first = [float(v) for v in lines[4].split(",")]
    assert lines[4] == ",".join(f"{v:.10g}" for v in first)  # %.10g, as before
    np.testing.assert_allclose(first[:3], cal.calibrated[0], rtol=1e-9)
