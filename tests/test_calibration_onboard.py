"""Say what the log already did (issue 33 item 6): a PX4 or ArduPilot log's onboard calibration, undone by its
reader, is named in the printed report, calibration.json and a refusal, with the spread of the readings as
logged, raw and held out from magexp's calibration."""

from __future__ import annotations

import json

import numpy as np
import pytest

import magexp
from magexp.calibration.command import main
from magexp.core.identifiability import spread
from magexp.core.readers.dataflash import read_dataflash
from magexp.core.readers.ulog import read_ulog
from magexp.core.recordings import load_recording
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

ULOG, ULOG_SMALL, DATAFLASH = (SHARED_DATA / n for n in ("px4_sample.ulg", "px4_sample_log_small.ulg",
                                                         "ardupilot_test.bin"))
needs = lambda path: pytest.mark.skipif(not path.is_file(), reason=f"{path} is not present")  # noqa: E731


def _as_logged_spread(path) -> float:
    """The spread of the log's readings as logged, read independently (the reader with undo=False)."""
    kept = (read_ulog if path.suffix == ".ulg" else read_dataflash)(path, undo=False)
    return spread(np.linalg.norm(kept.readings, axis=1))


@needs(ULOG)
def test_px4_report_and_json_name_the_undone_calibration_and_its_spreads(tmp_path, capsys):
    assert main([f"data.path={ULOG}", f"out={tmp_path / 'out'}", "accept=true", "model=sphere"]) == 0
    printed = capsys.readouterr().out
    line = next(x for x in printed.splitlines() if x.startswith("onboard calibration"))
    assert "PX4 CAL_MAG0_*" in line and "was undone" in line and "as logged (onboard-corrected) 1.6 %" in line
    record = json.loads((tmp_path / "out" / "calibration.json").read_text())["quality"]["onboard_calibration"]
    assert record["undone"] and record["parameters"] == "PX4 CAL_MAG0_*" and "S^-1 R^T B + OFF" in record["how"]
    assert record["spread_as_logged"] == pytest.approx(_as_logged_spread(ULOG), rel=1e-12)
    raw = spread(np.linalg.norm(load_recording(ULOG).readings, axis=1))
    assert record["spread_raw"] == pytest.approx(raw, rel=1e-12) and record["spread_raw"] != record["spread_as_logged"]
    held = json.loads((tmp_path / "out" / "calibration.json").read_text())["metrics"]["heldout_spread"]
    assert record["heldout_spread_magexp"] == pytest.approx(held)


@needs(ULOG)
def test_a_gate_refusal_of_a_log_quotes_magexps_held_out_spread_once():
    with pytest.raises(MagexpError) as err:
        magexp.calibrate(ULOG, model="sphere")
    line = str(err.value)
    assert "check 'heldout' failed" in line and line.count("onboard calibration (PX4") == 1
    assert line.endswith("raw 2.9 %, magexp's calibration held out 22.8 %")


@pytest.mark.parametrize("path, parameters", [(ULOG, "PX4 CAL_MAG0_*"), (ULOG_SMALL, "PX4 CAL_MAG1_*"),
                                              (DATAFLASH, "ArduPilot COMPASS_OFS_*")],
                         ids=["px4_sample", "px4_small", "ardupilot"])
def test_a_refused_log_says_what_its_firmware_did(path, parameters):
    """Each shared log is refused (the ellipsoid fit fails on too little coverage, one attitude, 8 readings): the
    line still says, once, that its onboard calibration was undone, and how the readings spread as logged."""
    if not path.is_file():
        pytest.skip(f"{path} is not present")
    with pytest.raises(MagexpError) as err:
        magexp.calibrate(path, model="full")
    line = str(err.value)
    assert "\n" not in line and parameters in line and line.count("was undone, the readings are raw") == 1
    assert f"as logged (onboard-corrected) {100 * _as_logged_spread(path):.3g} %" in line


def test_a_recording_without_onboard_calibration_says_nothing(tmp_path):
    rng = np.random.default_rng(2)
    d = rng.standard_normal((300, 3))
    cal = magexp.calibrate(40 * d / np.linalg.norm(d, axis=1, keepdims=True) + 3, unit="uT")
    assert "onboard_calibration" not in cal.report and "onboard calibration" not in cal.summary()
