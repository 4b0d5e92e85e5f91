"""magexp calibrate: a user's recording calibrated with any estimator, from one command, with its quality."""

import json
import numpy as np
import pytest
from hydra.utils import instantiate

from magexp.calibration.fit import calibrate_recording
from magexp.calibration.checks import MIN_READINGS
from magexp.calibration.inputs import attitude_of
from magexp.scenarios.search import search_box
from magexp.calibration.write import FILES, check_out
from magexp.errors import MagexpError
from magexp.paths import RESULTS, SHARED_DATA
from magexp.core.recordings import UNITS, load_recording
from magexp.run.runner import build
from magexp.core.geometry import ship_attitude

FXOS = SHARED_DATA / "fxos8700_mag_readings.txt"
needs_fxos = pytest.mark.skipif(not FXOS.is_file(), reason=f"{FXOS} is not present")


def calibrate(rec, est, **kw):
    return calibrate_recording(rec, est, folds=kw.pop("folds", 0), **kw)


def estimator(name, **overrides):
    from omegaconf import OmegaConf

    from magexp.run.compose import compose_config

    cfg = compose_config([f"estimator={name}"]).estimator  # typed by its schema
    return instantiate(OmegaConf.merge(cfg, overrides), _convert_="all")


@pytest.fixture
def magexp(cli):
    """``magexp(*args, cwd=...)``: ``magexp calibrate ARGS`` in-process (the ``cli`` fixture of conftest.py)."""
    import importlib.util

    if importlib.util.find_spec("magexp.calibration.command") is None:
        pytest.skip("the calibrate command (magexp.calibration.command) is not in this build")
    return lambda *args, cwd: cli("calibrate", *args, cwd=cwd)


def write_recording(path, readings, *, meta=(), extra=None):
    """A magexp-recording v1 file of ``readings`` (and ``extra`` columns ``{name: values}``)."""
    extra = extra or {}
    cols = np.column_stack([readings, *extra.values()]) if extra else readings
    lines = ["# magexp-recording v1", *meta, ",".join(["bx", "by", "bz", *extra])]
    lines += [",".join(f"{v:.12g}" for v in row) for row in cols]
    path.write_text("\n".join(lines) + "\n")
    return path


# -- the real recording, read in place ---------------------------------------------------------------
@needs_fxos
@pytest.mark.parametrize("name", ["ellipsoid", "lm"])
def test_fxos8700_spread_below_2_3_percent(name):
    rec = load_recording(FXOS, unit="uT")
    cal = calibrate(rec, estimator(name), rng=np.random.default_rng(0))
    print(f"{name}: spread {100 * cal.metrics['spread_before']:.3f} % -> {100 * cal.metrics['spread_after']:.3f} %")
    assert rec.n == 324 and rec.unit == "uT"
    assert cal.metrics["spread_before"] > 0.2
    assert cal.metrics["spread_after"] < 0.023
    assert cal.reference.estimated  # no reference in the file: the mean calibrated magnitude, and says so
    np.testing.assert_allclose(cal.metrics["mean_after"], cal.reference.total[0])


@pytest.mark.full  # 4 CPU-s (make test-full); make test: the command's files, overwrite=true and export in
# tests/test_calibration_files.py and test_calibration_folder.py, the figure drawn and saved beside in
# test_calibration_api.py, this recording's spread in test_fxos8700_spread_below_2_3_percent
@needs_fxos
def test_cli_end_to_end(tmp_path, magexp):
    results_before = sorted(p for p in RESULTS.rglob("*")) if RESULTS.exists() else []
    out = tmp_path / "calib"
    proc = magexp(f"data.path={FXOS}", "data.unit=uT", "estimator=lm", f"out={out}", "figure=true", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "spread after" in proc.stdout and "estimated as the mean calibrated magnitude" in proc.stdout
    assert {p.name for p in out.iterdir()} == set(FILES.values())
    params = json.loads((out / "calibration.json").read_text())
    assert params["unit"] == "uT" and params["estimator"] == "lm" and params["objective"] == "scalar"
    assert params["reference"]["estimated"] and "estimated" in params["reference"]["how"]
    assert np.shape(params["W"]) == (3, 3) and params["metrics"]["spread_after"] < 0.023
    again = load_recording(out / "calibrated.csv")  # the calibrated readings are a recording themselves
    np.testing.assert_allclose(np.linalg.norm(again.readings, axis=1), again.columns["magnitude"], rtol=1e-8)
    assert (out / "calibration.png").stat().st_size > 10_000
    assert (sorted(p for p in RESULTS.rglob("*")) if RESULTS.exists() else []) == results_before
    # a second run into the same folder refuses to overwrite
    proc = magexp(f"data.path={FXOS}", "data.unit=uT", f"out={out}", cwd=tmp_path)
    assert proc.returncode != 0 and "already holds" in proc.stderr and "Traceback" not in proc.stderr
    # unless told to: overwrite=true replaces them, and says so; without figure=true no figure is drawn
    proc = magexp(f"data.path={FXOS}", "data.unit=uT", f"out={out}", "overwrite=true", "export=px4", cwd=tmp_path)
    assert proc.returncode == 0 and "overwrite=true" in proc.stdout and "no figure" in proc.stdout, proc.stderr
    assert {p.name for p in out.iterdir()} == {"calibration.json", "calibrated.csv", "magexp_mag.params"}
    assert json.loads((out / "calibration.json").read_text())["estimator"] == "ellipsoid"


# -- a synthetic recording with a known calibration ---------------------------------------------------
@pytest.fixture
def ding(make_cfg):
    return instantiate(make_cfg("scenario=ding2024_exp1").scenario, _convert_="all")


def test_known_calibration_is_recovered_scalar(tmp_path, ding):
    ds = ding.generate(rng=np.random.default_rng(7))
    path = write_recording(tmp_path / "sim.csv", ds.readings / 1000, meta=["# unit: uT", "# reference_total: 51.5"])
    cal = calibrate(load_recording(path), estimator("lm"), rng=np.random.default_rng(0))
    assert np.linalg.norm(cal.offset * 1000 - ds.truth.offset) < 3.0  # nT, noise A = 2 nT
    w, wt = cal.w, ds.truth.matrix  # uT -> uT is nT -> nT: the same W (up to a rotation: scalar fit)
    np.testing.assert_allclose(w.T @ w, wt.T @ wt, atol=1e-3)
    np.testing.assert_allclose(w, w.T, atol=1e-12)  # the canonical (symmetric polar) form
    assert cal.metrics["rms_after"] * 1000 < 2.0 and not cal.reference.estimated


@pytest.mark.parametrize("name", ["lm", "ekf"])
def test_known_calibration_is_recovered_vector_with_attitudes(tmp_path, ding, name):
    rng = np.random.default_rng(3)
    angles = rng.uniform([0, -np.pi / 2, -np.pi / 2], [2 * np.pi, np.pi / 2, np.pi / 2], (200, 3))
    readings = ship_attitude(*angles.T) @ ding.field @ ding.m.T + ding.i + rng.normal(0, 1.0, (200, 3))
    field = ", ".join(f"{v:.12g}" for v in ding.field)
    path = write_recording(tmp_path / "vec.csv", readings, meta=["# unit: nT", f"# field: {field}"],
                           extra=dict(zip(("heading", "roll", "trim"), angles.T)))
    cal = calibrate(load_recording(path), estimator(name), objective="vector", rng=np.random.default_rng(0))
    assert np.linalg.norm(cal.offset - ding.i) < 2.0
    np.testing.assert_allclose(cal.w, np.linalg.inv(ding.m), atol=1e-4)  # the rotation too
    assert cal.metrics["vector_rms"] < 2.0


def test_gyro_rates_integrate_to_attitudes(tmp_path):
    n, rate = 20, 9.0  # deg/s about z, 0.5 s apart: 4.5 degrees per reading
    rows = np.column_stack([np.ones((n, 3)), np.tile([0.0, 0.0, rate], (n, 1))])
    path = tmp_path / "gyro.csv"
    path.write_text("# magexp-recording v1\n# unit: uT\n# gyro: deg/s\n# sample_time: 0.5\nbx,by,bz,gx,gy,gz\n"
                    + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    c = attitude_of(load_recording(path))
    assert c.shape == (n, 3, 3)
    np.testing.assert_allclose(c[0], np.eye(3), atol=1e-15)
    a = np.deg2rad(4.5 * (n - 1))  # nav -> body: the transpose of the body's turn
    np.testing.assert_allclose(c[-1], [[np.cos(a), np.sin(a), 0], [-np.sin(a), np.cos(a), 0], [0, 0, 1]], atol=1e-12)


def test_search_box_from_data():
    r = np.array([[-10.0, 0, 5], [30, 2, -4], [0, 1, 1]])
    from magexp.scenarios.search import centroid_radius

    box = search_box(r, 2 * centroid_radius(r))
    assert box.offset == (-10.0, 30.0)
    assert box.diag == pytest.approx((1.0, 3.0)) and box.offdiag == pytest.approx((-1, 1))


# -- the mock-up and the ship scenario ----------------------------------------------------------------
def test_mockup_still_loads_and_ship_needs_attitudes(tmp_path, make_cfg):
    rec = load_recording("yan2022_mockup.csv")
    assert rec.readings.shape == (12, 3) and rec.angles.shape == (12, 3) and rec.unit == "nT"
    ship = instantiate(make_cfg("scenario=yan2022_mockup").scenario, _convert_="all")
    assert ship.generate().n == 12
    path = write_recording(tmp_path / "noatt.csv", np.ones((12, 3)), meta=["# field: 1, 2, 3"])
    with pytest.raises(MagexpError, match="missing column heading, roll, trim") as err:
        build(make_cfg("scenario=yan2022_mockup", f"scenario.path={path}").scenario, "yan2022_mockup")
    assert "\n" not in str(err.value)


# -- bad input: one line, non-zero exit, no traceback -------------------------------------------------
ROWS = "\n".join(f"{i},{2 * i + 1},{-i}" for i in range(1, 16)) + "\n"
GOOD = "# magexp-recording v1\n# unit: uT\nbx,by,bz\n" + ROWS


@pytest.mark.parametrize("name, text, args, message", [
    ("missing_column", GOOD.replace("bx,by,bz", "bx,by,bq"), [], "missing column bz"),
    ("text", GOOD.replace("3,7,-3", "3,seven,-3"), [], "line 6: by='seven' is not a number"),
    ("nan", GOOD.replace("3,7,-3", "3,nan,-3"), [], "by='nan' is not allowed"),
    ("plain_text", ROWS.replace("3,7,-3", "3 x -3"), ["data.unit=uT"], "line 3: y='x' is not a number"),
    ("plain_nan", ROWS.replace("3,7,-3", "3\tNaN\t-3"), ["data.unit=uT"], "y='NaN' is not allowed"),
    ("few_rows", GOOD.split("\n4,")[0] + "\n", [],
     f"3 readings is not allowed: a calibration needs at least {MIN_READINGS}"),
    ("unit_file", GOOD.replace("uT", "gauss"), [], "unit='gauss' is not allowed: choose one of nT, uT, mG, G, T, counts"),
    ("unit_cli", ROWS, ["data.unit=furlong"], "data.unit='furlong' is not allowed: choose one of nT, uT"),
    ("no_unit", ROWS, [], "give data.unit="),
    ("four_columns", ROWS.replace("\n", ",1\n"), ["data.unit=uT"], "exactly 3 columns"),
])
def test_bad_input_is_one_line(tmp_path, magexp, name, text, args, message):
    path = tmp_path / f"{name}.csv"
    path.write_text(text)
    proc = magexp(f"data.path={path}", *args, f"out={tmp_path / 'out'}", "estimator=ellipsoid", cwd=tmp_path)
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert proc.returncode != 0 and len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert message in lines[0]
    assert not (tmp_path / "out").exists()


def test_missing_file_and_existing_output_are_one_line(tmp_path, magexp):
    proc = magexp(f"data.path={tmp_path / 'absent.csv'}", "data.unit=uT", f"out={tmp_path / 'o'}", cwd=tmp_path)
    assert proc.returncode != 0 and proc.stderr.count("\n") == 1 and "does not exist" in proc.stderr
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "calibrated.csv").write_text("mine\n")
    with pytest.raises(MagexpError, match="already holds calibrated.csv") as err:
        check_out(tmp_path / "out")
    assert "\n" not in str(err.value) and (tmp_path / "out" / "calibrated.csv").read_text() == "mine\n"
    with pytest.raises(MagexpError, match="results/"):
        check_out(RESULTS / "mine")


def test_estimator_that_does_not_apply_is_one_line(tmp_path):
    path = tmp_path / "ok.csv"
    path.write_text(GOOD)
    with pytest.raises(MagexpError, match="estimator='kf' is not allowed for objective 'scalar': choose one of") as err:
        calibrate(load_recording(path), estimator("kf"), rng=np.random.default_rng(0))
    assert "ellipsoid" in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(MagexpError, match="objective='vector' is not allowed"):
        calibrate(load_recording(path), estimator("lm"), objective="vector", rng=np.random.default_rng(0))


def test_units_are_carried():
    """A calibration is in its readings' unit: the same readings in uT, in mG (x10) and in raw counts
    give the same offset in each unit; the factors to nT are the SI ones."""
    from magexp import calibrate as calibrate_api
    from magexp.core.recordings import RAW_UNITS

    assert UNITS == {"nT": 1.0, "uT": 1e3, "mG": 100.0, "G": 1e5, "T": 1e9} and "counts" in RAW_UNITS
    t = np.linspace(0, 20, 80)
    sphere = np.column_stack([np.cos(t) * np.sin(t / 7 + 0.3), np.sin(t) * np.sin(t / 7 + 0.3), np.cos(t / 7 + 0.3)])
    readings = 40 * sphere * [1.02, 0.98, 1.0] + [3.0, -2.0, 1.0]  # uT
    offsets = {}
    for unit, factor in (("uT", 1.0), ("mG", 10.0), ("counts", 1.0)):
        cal = calibrate_api(readings * factor, unit=unit, estimator="ellipsoid")
        assert cal.unit == unit
        offsets[unit] = cal.offset / factor
    np.testing.assert_allclose(offsets["uT"], [3.0, -2.0, 1.0], atol=1e-6)
    np.testing.assert_allclose(offsets["mG"], offsets["uT"], rtol=1e-9)
    np.testing.assert_allclose(offsets["counts"], offsets["uT"], rtol=1e-9)


def test_reference_order_and_unit_agreement(tmp_path):
    from magexp.calibration.inputs import reference_of

    rows = np.column_stack([np.ones((12, 3)), np.arange(50.0, 62.0)])
    body = "\n".join(",".join(map(str, r)) for r in rows) + "\n"
    path = tmp_path / "ref.csv"
    path.write_text("# magexp-recording v1\n# unit: uT\n# reference_total: 53\n# field: 3, 4, 0\nbx,by,bz,total\n" + body)
    rec = load_recording(path, unit="µT")  # the same unit as the file's: accepted
    assert reference_of(rec, 40).source == "data.reference_total" and reference_of(rec, 40).total[0] == 40
    np.testing.assert_array_equal(reference_of(rec).total, np.arange(50.0, 62.0))  # the column first
    rec.total = None
    assert reference_of(rec).total[0] == 53
    rec.reference_total = None
    assert reference_of(rec).total[0] == 5 and not reference_of(rec).estimated
    with pytest.raises(MagexpError, match="data.unit='nT' is not allowed for ref.csv: the file says"):
        load_recording(path, unit="nT")


def test_a_closed_form_calibration_in_a_longer_process_leaves_the_compiled_kernels_on(tmp_path, magexp, monkeypatch):
    """The command computes a closed-form fit's residuals with numpy (its ``compiled`` choice, not an
    environment variable: none is set inside it), and leaves the process as it found it: run in a notebook
    or a test worker, it once turned numba off for everything after it (an order-dependent failure of the
    kernels' tests)."""
    import os

    from magexp.problems import kernels

    monkeypatch.delenv("MAGEXP_NUMBA", raising=False)
    kernels.compiled.cache_clear()
    try:
        assert kernels.compiled() is not None
        seen = []
        real = calibrate_recording
        monkeypatch.setattr("magexp.calibration.command.calibrate_recording",
                            lambda *a, **k: seen.append((os.environ.get("MAGEXP_NUMBA"), kernels.compiled())) or real(*a, **k))
        rng = np.random.default_rng(0)
        directions = rng.normal(size=(400, 3))
        field = 50.0 * directions / np.linalg.norm(directions, axis=1, keepdims=True)
        readings = field @ np.array([[1.1, 0.05, 0.0], [0.0, 0.95, 0.02], [0.0, 0.0, 1.02]]).T + [4.0, -3.0, 2.0]
        path = tmp_path / "sphere.csv"
        write_recording(path, readings + rng.normal(scale=0.05, size=readings.shape), meta=["# unit: uT"])
        proc = magexp(f"data.path={path}", "estimator=ellipsoid", f"out={tmp_path / 'o'}", cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert seen == [(None, None)]  # numpy inside the command, the environment untouched
        assert "MAGEXP_NUMBA" not in os.environ and kernels.compiled() is not None  # as it was, after it
    finally:  # the worker's own MAGEXP_NUMBA back, and the kernels' choice made again from it
        monkeypatch.undo()
        kernels.compiled.cache_clear()
