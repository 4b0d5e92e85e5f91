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
    proc = calibrate(f"data.path={path}", f"out={out}", f"export={target}", "overwrite=true", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (out / FILE_NAMES[target]).read_bytes() != before[FILE_NAMES[target]]
    assert sorted(snapshot(out)) == sorted([FILES["parameters"], FILES["readings"], FILE_NAMES[target]])


@pytest.mark.parametrize("target", ["ardupilot", "px4", "ros"])
def test_an_export_refused_after_the_fit_touches_nothing(tmp_path, calibrate, target):
    """A raw-count recording without counts_nt: the export refuses after the fit. The earlier
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
