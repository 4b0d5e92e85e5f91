"""The notebook API: a Calibration applies, saves, loads (exactly), summarises, plots and exports; the
reference from a field model is recorded as such (model, generation, place, date), with its provenance."""

import json

import numpy as np
import pytest

import magexp
from magexp import Calibration
from magexp.calibration.command import main
from magexp.core.geometry import random_rotations
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

M = np.array([[1.10, 0.05, -0.03], [0.05, 0.92, 0.04], [-0.03, 0.04, 1.05]])
OFFSET = np.array([12.0, -7.0, 4.0])


@pytest.fixture(scope="module")
def cal():
    rng = np.random.default_rng(3)
    u = random_rotations(500, rng=rng)[:, :, 0]
    return magexp.calibrate(50.0 * u @ M.T + OFFSET + rng.normal(0, 0.05, (500, 3)), unit="uT",
                            reference_total=50.0)


def test_load_of_save_applies_exactly(cal, tmp_path):
    path = cal.save(tmp_path / "c.json")
    back = Calibration.load(path)
    probe = np.random.default_rng(0).normal(0, 60, (1000, 3))
    assert np.array_equal(back.apply(probe), cal.apply(probe))  # bit for bit
    assert np.array_equal(cal.apply(cal.recording.readings), cal.calibrated)
    assert back.apply(probe[0]).shape == (3,)
    saved = json.loads(path.read_text())
    assert saved["format"] == "magexp-calibration v3" and saved["provenance"]["magexp_version"] == magexp.__version__
    assert saved["config"]["model"] == "auto" and saved["quality"]["model_selection"]["chosen"] == cal.model
    with pytest.raises(MagexpError, match="exists already"):
        cal.save(path)
    cal.save(path, overwrite=True)
    assert back.summary().splitlines()[0].startswith("recording") and "loaded" in back.summary()


def test_repr_is_short_and_summary_has_the_numbers(cal):
    text = repr(cal)
    assert len(text.splitlines()) == 1 and len(text) < 250 and "held out" in text and "gate passed" in text
    assert "spread after" in cal.summary() and "gate" in cal.summary()


def test_plot_returns_a_figure_and_export_writes_beside(cal, tmp_path):
    fig = cal.plot()
    assert type(fig).__name__ == "Figure" and len(fig.axes) == 7  # the heading-error panel too
    cells = round(cal.metrics["coverage_cells"] * 32)  # the map shows the report's coverage of the raw directions
    assert f"coverage: {cells} of 32 cells" in [ax.get_title() for ax in fig.axes]
    path = cal.export("ros", tmp_path)
    assert path.name == "magexp_mag_calibration.yaml" and "ros__parameters" in path.read_text()
    with pytest.raises(MagexpError, match="plot\\(\\) is not allowed for a loaded calibration"):
        Calibration.load(cal.save(tmp_path / "c.json")).plot()


@pytest.mark.parametrize("text, message", [("[1, 2]", "format 'list' is not allowed"),
                                           ('{"format": "magexp-calibration v3", "W": [1], "offset": [0]}',
                                            "the key .model. is missing"), ("not json", "not a calibration.json")])
def test_load_refuses_bad_files_in_one_line(tmp_path, text, message):
    (tmp_path / "bad.json").write_text(text)
    with pytest.raises(MagexpError, match=message):
        Calibration.load(tmp_path / "bad.json")


FXOS = SHARED_DATA / "fxos8700_mag_readings.txt"
QMC = SHARED_DATA / "qmc5883l_noisy_raw_data.csv"


@pytest.mark.skipif(not FXOS.is_file(), reason=f"{FXOS} is not present")
@pytest.mark.parametrize("keys, generation", [(["field.model=wmm", "field.latitude=52.2", "field.longitude=0.1",
                                                "field.date=2024-05-01"], "WMM-2020"),
                                               (["igrf.latitude=52.2", "igrf.longitude=0.1", "igrf.date=2024-05-01"],
                                                "IGRF-14")])
def test_a_field_model_reference_is_recorded_with_its_inputs(tmp_path, keys, generation):
    out = tmp_path / "o"
    assert main([f"data.path={FXOS}", "data.unit=uT", *keys, f"out={out}", "accept=true"]) == 0
    ref = json.loads((out / "calibration.json").read_text())["reference"]
    assert ref["source"].startswith(generation) and ref["field_model"]["generation"] == generation
    assert ref["field_model"]["latitude"] == 52.2 and ref["field_model"]["date"] == "2024-05-01"
    assert not ref["estimated"] and abs(ref["total"] - ref["field_model"]["total_nT"] / 1000) < 1e-9


@pytest.mark.skipif(not QMC.is_file(), reason=f"{QMC} is not present")
def test_raw_counts_are_calibrated_to_the_model_field_in_nt(tmp_path):
    out = tmp_path / "o"
    assert main([f"data.path={QMC}", "field.latitude=-34.6", "field.longitude=-58.4", "field.date=2024-01-01",
                 f"out={out}", "accept=true"]) == 0
    saved = json.loads((out / "calibration.json").read_text())
    assert (saved["unit"], saved["field_unit"], saved["reference"]["unit"]) == ("counts", "nT", "nT")
    assert abs(saved["metrics"]["mean_after"] / saved["reference"]["total"] - 1) < 0.01


def test_import_magexp_sets_no_thread_variables():
    """``import magexp`` (and the calibration API) leave the user's process environment alone."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    code = ("import os, magexp, magexp.calibration.command; "
            "print(sorted(k for k in os.environ if k.endswith('_NUM_THREADS')))")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_calibrate_help_lists_every_key_with_a_sentence(capsys):
    from omegaconf import OmegaConf

    from magexp.paths import CONF

    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    cfg = OmegaConf.load(CONF / "calibrate.yaml")
    keys = [f"{k}.{sub}" if sub else k for k, v in cfg.items() if k != "defaults"
            for sub in (v.keys() if OmegaConf.is_dict(v) else [None])]
    for key in keys:
        line = next(line for line in out.splitlines() if line.split() and line.split()[0] == key)
        assert len(line.split(":", 1)[1].strip()) > 3, line  # a sentence, not only the default


@pytest.mark.parametrize("missing, extra, code", [("cma", "cmaes", 2), ("distributed.client", "dask", 2),
                                                  ("pyulog", "ulog", 2), ("not_a_magexp_extra", None, 3)])
def test_a_missing_optional_package_names_its_extra(capsys, missing, extra, code):
    from magexp.errors import exit_code

    def needs():
        raise ModuleNotFoundError(f"No module named {missing!r}", name=missing)

    assert exit_code(needs) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and (extra is None or f"pip install 'magexp[{extra}]'" in err[0])


@pytest.mark.skipif(not FXOS.is_file(), reason=f"{FXOS} is not present")
@pytest.mark.parametrize("args, message", [
    (["igrf.latitude=52.2", "field.latitude=52.2"], "igrf.latitude=52.2 is not allowed with field.latitude"),
    (["field.latitude=52.2", "field.longitude=0.1"], "field.date=None is not allowed"),
    (["field.model=xyz", "field.latitude=1", "field.longitude=1", "field.date=2024-01-01"], "field.model='xyz'"),
    (["overwrite=yes"], "overwrite='yes' is not allowed"), (["export=betaflight"], "export='betaflight'"),
    (["gate.max_anisotropy=0"], "gate.max_anisotropy=0"),
])
def test_bad_new_keys_are_one_line_nothing_written(tmp_path, capsys, args, message):
    assert main([f"data.path={FXOS}", "data.unit=uT", *args, f"out={tmp_path / 'o'}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "o").exists()


def test_the_public_api_is_importable_from_the_root():
    """``from magexp import calibrate, Calibration, FitResult``: the API's own objects, not forwarders."""
    import inspect

    from magexp import FitResult, calibrate
    from magexp.calibration import api, result
    from magexp.estimators import result as estimator_result

    assert calibrate is api.calibrate and Calibration is result.Calibration and FitResult is estimator_result.FitResult
    assert {"calibrate", "Calibration", "FitResult"} <= set(dir(magexp))
    params = inspect.signature(calibrate).parameters
    keywords = [n for n, p in params.items() if p.kind is p.KEYWORD_ONLY]
    assert keywords[:12] == ["unit", "estimator", "objective", "reference_total", "folds", "seed", "checks", "model",
                             "accept", "gate", "auto_margin", "compiled"]
    with pytest.raises(AttributeError, match="no attribute 'calibrat'"):
        magexp.calibrat  # noqa: B018


def test_the_api_and_the_command_take_their_defaults_from_one_schema():
    """The defaults of ``calibrate``'s keywords are the schema's, and ``conf/calibrate.yaml`` is the schema's text."""
    import inspect

    from magexp.calibration.options import CONFIG, DEFAULTS, ESTIMATOR, yaml_text

    params = inspect.signature(magexp.calibrate).parameters
    for key in ("objective", "folds", "seed", "model", "accept", "auto_margin"):
        assert params[key].default == getattr(DEFAULTS, key), key
    assert params["estimator"].default == ESTIMATOR
    assert CONFIG.read_text() == yaml_text(), "run: python -m magexp.calibration.options --write"


def test_the_help_gives_each_key_its_type(capsys):
    assert main(["--help"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line.split()}
    assert lines["seed"].split()[1:3] == ["int", "0:"]
    assert lines["gate.scale_range"].split()[1:3] == ["[float,", "float]"]
    assert "str or null" in lines["data.unit"] and "float or null" in lines["counts_nt"]


def test_the_kernels_path_is_an_argument_not_the_environment(monkeypatch):
    """``compiled=False`` computes with numpy, ``None`` (a closed form) too, without touching ``MAGEXP_NUMBA``;
    both give the same calibration, and the process's choice is as it was after."""
    import os

    from magexp.calibration import fit
    from magexp.problems import kernels

    monkeypatch.delenv("MAGEXP_NUMBA", raising=False)
    seen, real = [], fit.calibrate_recording
    monkeypatch.setattr("magexp.calibration.api.calibrate_recording",
                        lambda *a, **k: seen.append((os.environ.get("MAGEXP_NUMBA"), kernels.fused_enabled()))
                        or real(*a, **k))
    rng = np.random.default_rng(5)
    u = random_rotations(300, rng=rng)[:, :, 0]
    readings = 50.0 * u @ M.T + OFFSET + rng.normal(0, 0.05, (300, 3))
    a = magexp.calibrate(readings, unit="uT", model="full", compiled=False)
    b = magexp.calibrate(readings, unit="uT", model="full")
    assert seen == [(None, False), (None, False)]  # numpy both times, the environment untouched
    assert np.array_equal(a.w, b.w) and a.config["compiled"] is False and "compiled" not in b.config
    assert fit.numpy_path(True, object()) is False and fit.numpy_path(None, object()) is False  # iterative: compiled
    with pytest.raises(MagexpError, match="compiled='yes' is not allowed: give compiled=true or compiled=false"):
        magexp.calibrate(readings, unit="uT", compiled="yes")


class _Broken:
    """A user's estimator whose fit raises its own error."""

    name = "broken"

    def fit(self, problem, rng=None):
        raise KeyError("its own bug")


@pytest.mark.parametrize("model, folds", [("full", 0), ("full", 6), ("auto", 6)])
def test_a_user_estimators_failure_is_one_line_naming_it_with_its_cause(cal, model, folds):
    """Issue 41 item 6: whatever the fit is (the whole recording, a held-out fold, ``model=auto``'s candidates), a
    user's estimator that raises is one MagexpError naming it, its own exception the ``__cause__`` (not an unfit
    fold counted as 'did not converge', nor a KeyError escaping)."""
    with pytest.raises(MagexpError, match="estimator='broken' failed: its fit raised KeyError") as err:
        magexp.calibrate(cal.recording.readings, unit="uT", estimator=_Broken(), model=model, folds=folds)
    assert isinstance(err.value.__cause__, KeyError) and len(str(err.value).splitlines()) == 1


def test_every_file_a_loaded_calibration_came_from_reloads_and_a_resave_round_trips(cal, tmp_path):
    """The schema accepts the calibration.json magexp writes and the copy saved again from the loaded calibration."""
    first = Calibration.load(cal.save(tmp_path / "a.json"))
    again = Calibration.load(first.save(tmp_path / "b.json"))
    assert np.array_equal(again.w, cal.w) and again.saved == first.saved


@pytest.mark.full
def test_load_in_a_process_never_waits_on_a_fifo_nor_reads_a_device(tmp_path):
    """A FIFO or ``/dev/zero`` given to ``Calibration.load`` in a real process: one MagexpError line, at once."""
    import os
    import subprocess
    import sys

    os.mkfifo(tmp_path / "pipe.json")
    script = ("import sys, magexp\nfrom magexp.errors import MagexpError\nfor p in sys.argv[1:]:\n"
              "    try:\n        magexp.Calibration.load(p)\n    except MagexpError as e:\n        print(e)\n")
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path / "pipe.json"), "/dev/zero"],
                          capture_output=True, text=True, timeout=60)
    lines = done.stdout.splitlines()
    assert len(lines) == 2 and "a FIFO" in lines[0] and "character device" in lines[1], done.stdout + done.stderr
