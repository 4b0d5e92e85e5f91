"""A calibration that says how good it is: canonical W, standard errors, coverage, held-out spread,
and degenerate data refused in one line with nothing written."""

import json

import numpy as np
import pandas as pd
import pytest

import magexp
from magexp.calibration.command import main
from magexp.errors import MagexpError
from magexp.core.geometry import random_rotations
from magexp.paths import SHARED_DATA
from magexp.core.identifiability import canonical, coverage

FXOS = SHARED_DATA / "fxos8700_mag_readings.txt"
needs_fxos = pytest.mark.skipif(not FXOS.is_file(), reason=f"{FXOS} is not present")

M = np.array([[1.10, 0.05, -0.03], [0.02, 0.92, 0.04], [-0.06, 0.01, 1.05]])
OFFSET = np.array([12.0, -7.0, 4.0])


def sphere_readings(n=400, noise=0.05, seed=1, directions=None):
    """Readings ``M u + o + noise`` of a 50 uT field seen from random directions (or ``directions``)."""
    rng = np.random.default_rng(seed)
    u = directions if directions is not None else random_rotations(n, rng=rng)[:, :, 0]
    return 50.0 * u @ M.T + OFFSET + rng.normal(0, noise, (len(u), 3))


def test_canonical_form_is_the_symmetric_polar_factor():
    q = random_rotations(1, rng=np.random.default_rng(0))[0]
    p = canonical(q @ np.linalg.inv(M))
    np.testing.assert_allclose(p, p.T, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(p) > 0)
    np.testing.assert_allclose(p.T @ p, np.linalg.inv(M).T @ np.linalg.inv(M), atol=1e-12)


@pytest.mark.full  # two full calibrations, one by a swarm
def test_ipso_w_equals_ellipsoid_w_up_to_the_noise():
    r = sphere_readings()
    ell = magexp.calibrate(r, unit="uT", estimator="ellipsoid", reference_total=50.0, folds=0)
    ips = magexp.calibrate(r, unit="uT", estimator="ipso", reference_total=50.0, folds=0, seed=3)
    print("ipso - ellipsoid W:", np.abs(ips.w - ell.w).max(), "standard errors:", np.max(ell.report["W_standard_errors"]))
    assert "polar factor" in ips.report["w_form"]
    # no hidden rotation: a rotation of 1 degree would move entries by ~0.017
    assert np.abs(ips.w - ell.w).max() < 5 * np.max(ell.report["W_standard_errors"]) + 2e-3
    np.testing.assert_allclose(ips.offset, ell.offset, atol=0.05)


def test_standard_errors_coverage_and_heldout_on_a_full_sphere():
    cal = magexp.calibrate(pd.DataFrame(sphere_readings(), columns=["x", "y", "z"]), unit="uT", estimator="lm",
                           reference_total=50.0)
    m, rep = cal.metrics, cal.report
    np.testing.assert_allclose(cal.w, canonical(np.linalg.inv(M)), atol=5e-3)
    np.testing.assert_allclose(cal.offset, OFFSET, atol=0.05)
    assert 0 < max(rep["offset_standard_errors"]) < 0.05  # noise 0.05 uT over 400 readings
    assert rep["undetermined"] == [] and rep["condition_number"] < 100
    assert m["coverage_cells"] > 0.9 and m["coverage_lambda_min"] > 0.25
    assert m["spread_after"] < m["heldout_spread"] < 3 * m["spread_after"] + 1e-3


def test_half_sphere_coverage_is_measured():
    u = random_rotations(2000, rng=np.random.default_rng(2))[:, :, 0]
    half = coverage(u[u[:, 2] < 0])
    full = coverage(u)
    assert full["coverage_cells"] == 1.0 and 0.4 < half["coverage_cells"] < 0.75  # cells astride the equator count
    assert half["coverage_lambda_min"] < full["coverage_lambda_min"]


# -- degenerate cases: one line, nothing written ------------------------------------------------------
def _degenerate(kind):
    if kind == "identical":
        return np.tile([10.0, 20.0, 30.0], (40, 1)), "distinct readings"
    if kind == "plane":  # one turn about z: directions in the xy plane
        a = np.linspace(0, 2 * np.pi, 200, endpoint=False)
        return sphere_readings(directions=np.column_stack([np.cos(a), np.sin(a), 0 * a]), noise=0.0), "one plane"
    if kind == "one_attitude":  # readings jittering around one direction
        rng = np.random.default_rng(4)
        u = np.array([0.3, 0.5, 0.81]) + rng.normal(0, 0.02, (60, 3))
        return sphere_readings(directions=u / np.linalg.norm(u, axis=1, keepdims=True)), "barely move"
    if kind == "few_directions":  # four attitudes, many readings each
        rng = np.random.default_rng(5)
        base = random_rotations(4, rng=rng)[:, :, 0]
        return sphere_readings(directions=np.repeat(base, 30, axis=0)), "sphere cells|reports failure|single attitude"
    raise KeyError(kind)


@pytest.mark.parametrize("kind", ["identical", "plane", "one_attitude", "few_directions"])
@pytest.mark.parametrize("name", ["ellipsoid", "lm", "ipso"])
def test_degenerate_data_is_refused(kind, name):
    r, message = _degenerate(kind)
    budget = {"ipso": {"n_iterations": 60}, "lm": {"max_nfev": 200}}.get(name, {})  # the same refusal, sooner
    with pytest.raises(MagexpError, match=message) as err:
        magexp.calibrate(r, unit="uT", estimator=name, folds=0, **budget)
    assert "\n" not in str(err.value) and ("record" in str(err.value) or "turn the sensor" in str(err.value)
                                           or "try estimator" in str(err.value))


def test_estimator_failure_is_refused():
    class Failing:
        name = "failing"

        def fit(self, problem, *, rng=None):
            from magexp.estimators.result import FitResult

            x = (problem.lower + problem.upper) / 2
            return FitResult(x=x, fun=1.0, nit=1, nfev=1, history=np.ones(1), history_nfev=np.ones(1),
                             success=False, message="did not converge")

    with pytest.raises(MagexpError, match="estimator='failing' reports failure \\(did not converge\\)"):
        magexp.calibrate(sphere_readings(), unit="uT", estimator=Failing(), folds=0)


def _write(path, text):
    path.write_text(text)
    return path


def _cli(tmp_path, *args):
    return main([*args, f"out={tmp_path / 'out'}"])


@needs_fxos
@pytest.mark.parametrize("name", ["lm", "ellipsoid"])
def test_first_12_fxos_readings_exit_nonzero_nothing_written(tmp_path, capsys, name):
    rows = FXOS.read_text().splitlines()[:12]
    path = _write(tmp_path / "first12.txt", "\n".join(rows) + "\n")
    assert _cli(tmp_path, f"data.path={path}", "data.unit=uT", f"estimator={name}") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: first12.txt: the readings barely move"), err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kind", ["identical", "plane"])
def test_cli_degenerate_one_line(tmp_path, capsys, kind):
    r, message = _degenerate(kind)
    path = _write(tmp_path / f"{kind}.txt", "\n".join(" ".join(map(str, row)) for row in r) + "\n")
    assert _cli(tmp_path, f"data.path={path}", "data.unit=uT") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "out").exists()


HEAD = "# magexp-recording v1\n# unit: uT\n"


@pytest.mark.parametrize("text, message", [
    (HEAD + "# reference_total: -50\nbx,by,bz\n" + "1,2,3\n" * 12, "reference_total='-50' is not allowed: it must be > 0"),
    (HEAD + "bx,by,bz,by\n" + "1,2,3,4\n" * 12, "column 'by' is duplicated"),
    (HEAD + "bx,by,bz,total\n" + "1,2,3,50\n" * 5 + "1,2,3,0\n" + "1,2,3,50\n" * 6, "total=0 is not allowed: it must be > 0"),
])
def test_bad_metadata_is_one_line(tmp_path, capsys, text, message):
    path = _write(tmp_path / "bad.csv", text)
    assert _cli(tmp_path, f"data.path={path}") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "out").exists()


@needs_fxos
def test_cli_writes_the_quality_report(tmp_path, capsys):
    assert _cli(tmp_path, f"data.path={FXOS}", "data.unit=uT", "estimator=lm", "folds=3") == 0
    out = capsys.readouterr().out
    assert "held-out spread" in out and "polar factor" in out and "coverage" in out
    params = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert params["format"] == "magexp-calibration v3" and "polar factor" in params["W_form"]
    assert params["metrics"]["heldout_folds"] == 6 and params["metrics"]["heldout_spread"] > params["metrics"]["spread_after"]
    assert min(params["metrics"]["direction_regions"]) > 0.05  # the six regions of directions, each held out
    np.testing.assert_allclose(params["W"], np.transpose(params["W"]), atol=1e-12)
    assert len(params["quality"]["offset_standard_errors"]) == 3


def test_array_api_rejects_bad_input():
    with pytest.raises(MagexpError, match="unit=None is not allowed"):
        magexp.calibrate(np.ones((20, 3)))
    with pytest.raises(MagexpError, match=r"shape \(20, 2\)"):
        magexp.calibrate(np.ones((20, 2)), unit="uT")
    with pytest.raises(MagexpError, match="estimator='nope' is not allowed"):
        magexp.calibrate(sphere_readings(), unit="uT", estimator="nope")


def test_half_sphere_full_model_fails_and_sphere_model_fits():
    u = random_rotations(600, rng=np.random.default_rng(6))[:, :, 0]
    u = u[u[:, 2] < -0.3]  # less than half the sphere
    r = 50.0 * u * 1.02 + OFFSET + np.random.default_rng(7).normal(0, 0.05, (len(u), 3))  # one scale only
    with pytest.raises(MagexpError, match="reach 5 of the 6 regions"):  # untested toward +z: refused
        magexp.calibrate(r, unit="uT", model="sphere", reference_total=50.0, folds=3)
    cal = magexp.calibrate(r, unit="uT", model="sphere", reference_total=50.0, folds=3, accept=True)
    np.testing.assert_allclose(cal.offset, OFFSET, atol=0.1)
    np.testing.assert_allclose(cal.w, np.eye(3) / 1.02, atol=2e-3)
    assert "model=sphere" in cal.report["w_form"] and cal.metrics["heldout_spread"] < 0.005
    with pytest.raises(MagexpError, match="model='sphere' is not allowed with objective 'vector'"):
        magexp.calibrate(r, unit="uT", model="sphere", objective="vector")
