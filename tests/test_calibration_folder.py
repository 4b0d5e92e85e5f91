"""One calibration per output folder (issue 40, item 6): calibration.json lists the files its calibration
wrote; overwrite=true replaces that whole set (what the new one does not write is removed and named), never
touches a file no calibration wrote (in the way: refused in one line), and a folder holding the recording is
refused; Calibration.save and .export follow the same rules."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import magexp
from magexp.calibration import write as write_mod
from magexp.calibration.command import main
from magexp.calibration.export import FILE_NAMES
from magexp.calibration.folder import check_recording, manifest, recording_files
from magexp.calibration.write import FILES, write
from magexp.core.recordings import load_recording
from magexp.errors import MagexpError
from magexp.paths import ROOT
from tests.test_calibration_files import snapshot, sphere_recording


@pytest.fixture(scope="module")
def cal():
    rng = np.random.default_rng(4)
    u = rng.standard_normal((300, 3))
    u *= 50.0 / np.linalg.norm(u, axis=1, keepdims=True)
    readings = u @ np.diag([1.05, 0.97, 1.01]).T + [4.0, -2.0, 6.0] + rng.normal(0, 0.05, u.shape)
    return magexp.calibrate(readings, unit="uT", model="full", folds=0)


def test_the_manifest_lists_every_other_file_with_its_digest(cal, tmp_path):
    paths = write(cal, tmp_path / "out", export="ros")
    listed = manifest(tmp_path / "out")
    assert sorted(listed) == sorted([FILES["readings"], FILE_NAMES["ros"]])
    assert json.loads(paths["parameters"].read_text())["files"] == listed
    assert paths.removed == ()


def test_overwrite_removes_the_earlier_exports_and_names_them(cal, tmp_path):
    out = tmp_path / "out"
    write(cal, out, export="ardupilot")
    paths = write(cal, out, overwrite=True, export="px4")
    assert paths.removed == (out / FILE_NAMES["ardupilot"],)
    assert sorted(p.name for p in out.iterdir()) == sorted([*list(FILES.values())[:2], FILE_NAMES["px4"]])
    paths = write(cal, out, overwrite=True)  # no export now: the px4 file goes too
    assert paths.removed == (out / FILE_NAMES["px4"],) and sorted(manifest(out)) == [FILES["readings"]]


def test_overwrite_never_touches_a_file_no_calibration_wrote(cal, tmp_path):
    out = tmp_path / "out"
    write(cal, out, export="c")
    (out / FILES["figure"]).write_bytes(b"\x89PNG the user's own picture")
    (out / "notes.txt").write_text("my notes\n")
    paths = write(cal, out, overwrite=True)
    assert paths.removed == (out / FILE_NAMES["c"],)
    assert (out / FILES["figure"]).read_bytes() == b"\x89PNG the user's own picture"
    assert (out / "notes.txt").read_text() == "my notes\n"


def test_a_user_file_in_the_way_is_refused_and_nothing_changes(cal, tmp_path):
    out = tmp_path / "out"
    write(cal, out)
    (out / FILES["figure"]).write_bytes(b"the user's own picture")
    before = snapshot(out)
    with pytest.raises(MagexpError, match="calibration.png is in the way and no calibration wrote it") as err:
        write(cal, out, overwrite=True, draw=True)
    assert "\n" not in str(err.value) and snapshot(out) == before


def test_an_earlier_export_changed_since_is_refused_not_removed(cal, tmp_path):
    out = tmp_path / "out"
    write(cal, out, export="ardupilot")
    param = out / FILE_NAMES["ardupilot"]
    param.write_text(param.read_text() + "COMPASS_USE,1\n")  # the user edited it
    before = snapshot(out)
    with pytest.raises(MagexpError, match="magexp_compass.param was written by the calibration in it and changed"):
        write(cal, out, overwrite=True, export="px4")
    with pytest.raises(MagexpError, match="magexp_compass.param is in the way"):
        write(cal, out, overwrite=True, export="ardupilot")
    assert snapshot(out) == before


def test_a_folder_written_before_the_manifest_is_replaced_by_its_marks(cal, tmp_path):
    out = tmp_path / "out"
    write(cal, out, export="ardupilot")
    params = json.loads((out / FILES["parameters"]).read_text())
    del params["files"]
    (out / FILES["parameters"]).write_text(json.dumps(params))
    (out / FILES["figure"]).write_bytes(b"a picture: no mark, not removed")
    paths = write(cal, out, overwrite=True, export="px4")
    assert paths.removed == (out / FILE_NAMES["ardupilot"],) and (out / FILES["figure"]).exists()


def test_an_export_written_beside_by_the_api_goes_with_the_set(cal, tmp_path):
    out = tmp_path / "out"
    write(cal, out, export="px4")
    cal.export("ros", out)  # not in the manifest, but magexp's own file
    paths = write(cal, out, overwrite=True, export="px4")
    assert paths.removed == (out / FILE_NAMES["ros"],)


def test_a_failure_while_writing_leaves_the_earlier_calibration_whole(cal, tmp_path, monkeypatch):
    out = tmp_path / "out"
    write(cal, out, export="ardupilot")
    before = snapshot(out)

    def fail(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(write_mod, "write_readings", fail)
    with pytest.raises(KeyboardInterrupt):
        write(cal, out, overwrite=True, export="px4")
    assert snapshot(out) == before


#: a process whose write is interrupted by Ctrl-C as each file of the new set moves into place (the main
#: thread: where signals are held; a pytest-xdist worker runs a test in another thread)
INTERRUPTED = """
import os, signal, sys
import numpy as np
import magexp
from magexp.calibration import write as w
rng = np.random.default_rng(4)
u = rng.standard_normal((300, 3))
cal = magexp.calibrate(50 * u / np.linalg.norm(u, axis=1, keepdims=True) + 3, unit="uT", model="sphere", folds=0)
out = sys.argv[1]
signal.signal(signal.SIGINT, signal.default_int_handler)  # a test run started as a background job inherits it ignored
w.write(cal, out, export="ardupilot")
replace = os.replace
def interrupted(src, dst):
    if os.path.dirname(dst) == out:
        os.kill(os.getpid(), signal.SIGINT)
    replace(src, dst)
w.os.replace = interrupted
try:
    w.write(cal, out, overwrite=True, export="px4")
except KeyboardInterrupt:
    print("interrupted")
"""


@pytest.mark.full  # a process of its own: 2.4 s
def test_ctrl_c_during_the_swap_waits_for_the_whole_new_set(tmp_path):
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-c", INTERRUPTED, str(out)], capture_output=True, text=True, timeout=120,
                          cwd=ROOT)
    assert proc.stdout.strip() == "interrupted", proc.stderr
    assert sorted(p.name for p in out.iterdir()) == sorted([FILES["parameters"], FILES["readings"], FILE_NAMES["px4"]])
    assert sorted(manifest(out)) == sorted([FILES["readings"], FILE_NAMES["px4"]])


def test_the_command_refuses_an_out_folder_holding_the_recording(tmp_path, capsys):
    out = tmp_path / "out"
    path = sphere_recording(tmp_path / "mine.csv")
    assert main([f"data.path={path}", f"out={out}"]) == 0
    capsys.readouterr()
    before = snapshot(out)
    assert main([f"data.path={out / FILES['readings']}", f"out={out}", "overwrite=true"]) == 2
    err = capsys.readouterr().err
    assert "holds the recording being read (calibrated.csv)" in err and err.count("\n") == 1, err
    assert snapshot(out) == before
    assert main([f"data.path={path}", f"out={tmp_path}"]) == 2  # the recording's own folder
    assert "holds the recording" in capsys.readouterr().err


def test_the_command_names_what_overwrite_removed(tmp_path, capsys):
    out, path = tmp_path / "out", sphere_recording(tmp_path / "mine.csv")
    assert main([f"data.path={path}", f"out={out}", "export=ardupilot"]) == 0
    assert main([f"data.path={path}", f"out={out}", "overwrite=true", "export=px4"]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("removed")]
    assert lines and str(out / FILE_NAMES["ardupilot"]) in lines[0], lines
    assert not (out / FILE_NAMES["ardupilot"]).exists()


def test_links_and_two_stream_files_in_out_are_the_recording(tmp_path):
    elsewhere, out = tmp_path / "elsewhere", tmp_path / "out"
    elsewhere.mkdir()
    out.mkdir()
    rec = sphere_recording(elsewhere / "rec.csv")
    os.link(rec, out / "hard.csv")
    with pytest.raises(MagexpError, match=r"holds the recording being read \(rec.csv\)"):
        check_recording(out, [rec])
    (out / "hard.csv").unlink()
    check_recording(out, [rec])  # nothing of it in out
    (elsewhere / "link.csv").symlink_to(out / "target.csv")
    sphere_recording(out / "target.csv")
    with pytest.raises(MagexpError, match="holds the recording"):
        check_recording(out, recording_files(load_recording(elsewhere / "link.csv", unit="uT")))
    t = np.arange(40) * 0.01
    (out / "s_mag.csv").write_text("t_s,mx_uT,my_uT,mz_uT\n" + "".join(f"{v},1,2,3\n" for v in t))
    (out / "s_imu.csv").write_text("t_s,gx_dps,gy_dps,gz_dps\n" + "".join(f"{v},0,0,0\n" for v in t))
    two = load_recording(out / "s")
    assert [p.name for p in recording_files(two)] == ["s_mag.csv", "s_imu.csv"]
    for files in ([out / "s_imu.csv"], recording_files(two)):
        with pytest.raises(MagexpError, match="holds the recording"):
            check_recording(out, files)


def test_save_and_export_replace_only_a_calibrations_file(cal, tmp_path):
    saved = cal.save(tmp_path / "c.json")
    with pytest.raises(MagexpError, match="exists already"):
        cal.save(saved)
    cal.save(saved, overwrite=True)
    mine = tmp_path / "mine.json"
    mine.write_text('{"my": "settings"}\n')
    with pytest.raises(MagexpError, match="no calibration wrote it") as err:
        cal.save(mine, overwrite=True)
    assert "\n" not in str(err.value) and mine.read_text() == '{"my": "settings"}\n'
    first = cal.export("px4", tmp_path)
    with pytest.raises(MagexpError, match="exists already"):
        cal.export("px4", tmp_path)
    assert cal.export("px4", tmp_path, overwrite=True) == first
    own = tmp_path / "own.params"
    own.write_text("1\t1\tCAL_MAG0_XOFF\t0.1\t9\n")
    with pytest.raises(MagexpError, match="no calibration wrote it"):
        cal.export("px4", own, overwrite=True)
    assert own.read_text() == "1\t1\tCAL_MAG0_XOFF\t0.1\t9\n"


def test_save_never_writes_over_the_recording(tmp_path):
    out = tmp_path / "out"
    assert main([f"data.path={sphere_recording(tmp_path / 'mine.csv')}", f"out={out}"]) == 0
    rec_path = out / FILES["readings"]  # a calibrated.csv carries magexp's mark: the recording all the same
    again = magexp.calibrate(str(rec_path), model="full", folds=0)
    before = rec_path.read_bytes()
    for act in (lambda: again.save(rec_path, overwrite=True),
                lambda: again.export("c", rec_path, overwrite=True)):
        with pytest.raises(MagexpError, match="it is the recording being read"):
            act()
    assert rec_path.read_bytes() == before
