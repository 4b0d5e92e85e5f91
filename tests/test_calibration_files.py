"""magexp calibrate never destroys a file: a refused run writes nothing and removes nothing it did not
create; a file that exists is replaced only with overwrite=true (issue 33, item 2)."""

from __future__ import annotations

import numpy as np
import pytest

from magexp.calibration.export import FILE_NAMES, TARGETS
from magexp.calibration.write import FILES
from magexp.core.geometry import random_rotations
from tests.test_calibrate import write_recording


def sphere_recording(path, *, unit="uT", n=400, seed=5):
    """A full-sphere recording of a known soft- and hard-iron distortion (field 50 in ``unit``)."""
    rng = np.random.default_rng(seed)
    directions = rng.standard_normal((n, 3))
    field = 50.0 * directions / np.linalg.norm(directions, axis=1, keepdims=True)
    q = random_rotations(1, rng=rng)[0]
    distortion = q @ np.diag([1.1, 0.95, 1.02]) @ q.T
    readings = field @ np.linalg.inv(distortion).T + np.array([7.0, -4.0, 12.0]) + rng.normal(0, 0.05, (n, 3))
    return write_recording(path, readings, meta=[f"# unit: {unit}"])


def snapshot(folder):
    """``{name: bytes}`` of every entry of ``folder`` (hidden ones included)."""
    return {p.name: p.read_bytes() if p.is_file() else None for p in folder.iterdir()}


@pytest.fixture
def calibrate(cli):
    return lambda *args, cwd: cli("calibrate", *args, cwd=cwd)


@pytest.mark.parametrize("target", TARGETS)
def test_an_existing_export_file_survives_a_refused_run(tmp_path, calibrate, target):
    path = sphere_recording(tmp_path / "mine.csv")
    out = tmp_path / "out"
    out.mkdir()
    (out / FILE_NAMES[target]).write_bytes(b"the user's own parameters\n\x00\xff")
    before = snapshot(out)
    proc = calibrate(f"data.path={path}", f"out={out}", f"export={target}", cwd=tmp_path)
    assert proc.returncode == 2 and "never overwritten" in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr
    assert FILE_NAMES[target] in proc.stderr
    assert snapshot(out) == before  # byte for byte, and no new file (nor a staging folder)
    # overwrite=true replaces a calibration's files only: the user's own is refused, named, untouched (issue 40)
    proc = calibrate(f"data.path={path}", f"out={out}", f"export={target}", "overwrite=true", cwd=tmp_path)
    assert proc.returncode == 2 and "no calibration wrote it" in proc.stderr and FILE_NAMES[target] in proc.stderr
    assert proc.stderr.count("\n") == 1 and snapshot(out) == before


@pytest.mark.parametrize("target", ["ardupilot", "px4", "ros"])
def test_a_refused_export_touches_nothing(tmp_path, calibrate, target):
    """A raw-count recording without counts_nt: the export refuses (before the fit). The earlier
    calibration in out (overwrite=true) stays byte for byte, a new folder is not created."""
    path = sphere_recording(tmp_path / "counts.csv", unit="counts")
    out = tmp_path / "out"
    proc = calibrate(f"data.path={path}", f"out={out}", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    before = snapshot(out)
    for folder, extra in ((out, ["overwrite=true"]), (tmp_path / "new" / "deeper", [])):
        proc = calibrate(f"data.path={path}", f"out={folder}", f"export={target}", *extra, cwd=tmp_path)
        assert proc.returncode == 2 and "counts_nt=" in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr
    assert snapshot(out) == before
    assert not (tmp_path / "new").exists()


# -- a CSV whose first row names its columns (issue 33, item 5) ----------------------------------------
def header_csv(path, header: str, readings, extra=None, sep=","):
    """``readings`` (and ``extra`` columns before them) under the header row ``header``."""
    table = readings if extra is None else np.column_stack([extra, readings])
    path.write_text(header + "\n" + "\n".join(sep.join(f"{v:.12g}" for v in row) for row in table) + "\n")
    return path


@pytest.mark.parametrize("header, extra_columns, sep, args", [
    ("x,y,z", 0, ",", ["data.unit=uT"]),
    ("mx,my,mz", 0, ",", ["data.unit=uT"]),
    ("ax,ay,az,mx,my,mz", 3, ",", ["data.unit=uT"]),
    ("t\tax\tay\taz\tgx_dps\tgy_dps\tgz_dps\tmx_uT\tmy_uT\tmz_uT", 7, "\t", []),
    ("time;mx (uT);my (uT);mz (uT)", 1, ";", []),
])
def test_a_header_row_csv_calibrates_through_the_cli_and_the_api(tmp_path, calibrate, header, extra_columns, sep,
                                                                   args):
    import magexp
    from magexp.core.recordings import load_recording

    plain = sphere_recording(tmp_path / "plain.csv")
    readings = load_recording(plain).readings
    rng = np.random.default_rng(1)
    extra = np.column_stack([np.arange(len(readings)) * 0.01, rng.normal(size=(len(readings), extra_columns - 1))]) \
        if extra_columns else None
    path = header_csv(tmp_path / "named.csv", header, readings, extra, sep)
    rec = load_recording(path, unit=None if not args else "uT")
    assert rec.meta["format"] == "header-row" and rec.unit == "uT"
    np.testing.assert_array_equal(rec.readings, readings)
    if "gx_dps" in header:  # the gyroscope in deg/s, on the time column
        times, rates = rec.gyro_rates()
        np.testing.assert_allclose(rates, np.deg2rad(extra[:, 4:7]), rtol=1e-10)  # %.12g in the file
        np.testing.assert_allclose(times, extra[:, 0], rtol=1e-12)
    proc = calibrate(f"data.path={path}", *args, f"out={tmp_path / 'out'}", "model=full", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    api = magexp.calibrate(str(path), unit=None if not args else "uT", model="full", folds=0)
    reference = magexp.calibrate(readings, unit="uT", model="full", folds=0)  # the same numbers as an array
    np.testing.assert_array_equal(api.w, reference.w)
    assert api.metrics["spread_after"] < 0.1 * api.metrics["spread_before"]


@pytest.mark.parametrize("header, args, message", [
    ("mx,my,mz", [], "give data.unit="),
    ("mx_uT,my_uT,mz_G", [], "give the three columns one unit"),
    ("mx_uT,my_uT,mz_uT", ["data.unit=nT"], "the file's columns say uT"),
    ("mx,my,mz,gx,gy,gz", ["data.unit=uT"], "need a time column"),
])
def test_a_header_row_csv_with_bad_metadata_is_one_line(tmp_path, calibrate, header, args, message):
    values = np.random.default_rng(2).normal(size=(30, len(header.split(","))))
    path = header_csv(tmp_path / "bad.csv", header, values)
    proc = calibrate(f"data.path={path}", *args, f"out={tmp_path / 'out'}", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and message in proc.stderr, proc.stderr
    assert not (tmp_path / "out").exists()
