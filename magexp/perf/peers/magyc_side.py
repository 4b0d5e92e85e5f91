"""The peer's side of the magexp / MAGYC bench: run in MAGYC's own environment (``.peers/venv``), never in magexp's.

This file imports numpy, the standard library and ``magyc`` only (magyc pins numpy < 2, jax < 0.5 and
needs gtsam: it cannot live in magexp's environment), and magexp never imports magyc. The two talk through
files (:mod:`magexp.perf.peers.exchange` documents the format):

``python magyc_side.py IN.npz OUT.json [IN2.npz OUT2.json ...]``
    for each pair, reads one neutral dataset (``IN.npz`` and its sidecar ``IN.json``), calls every MAGYC method named in the
    sidecar's ``methods`` (all of :data:`METHODS` when it names none) and writes their estimates (soft iron, hard iron, gyro bias, seconds) to ``OUT.json``.

``python magyc_side.py synth OUT_DIR SEED NSAMPLES``
    runs MAGYC's own generator (:func:`magyc.create_synthetic_dataset`, the fixed soft iron, hard iron and gyro
    bias of its docstring) at the settings of the MAGYC paper's Monte Carlo simulation (:data:`PAPER`) for one
    simulation per motion level with numpy's global generator
    seeded by ``SEED`` (the generator draws from it), and exports every motion level as a neutral dataset
    ``OUT_DIR/magyc_<level>_s<SEED>.npz`` with the truth.

Conventions (MAGYC 1.0.0, read from its source): a reading is ``m = SI m_true + HI`` with ``SI`` symmetric
positive definite. MAGYC-LS, -NLS, -BFG and -IFG fix ``det SI = 1`` (the gyroscope sees directions, not
scale). ``ellipsoid_fit`` returns the *correction* ``SI^-1`` (det 1) under the name ``soft_iron``: recorded
here as ``convention: correction``; its eigenvalues are right, its axes are not (it transposes the eigenvector
matrix, ``evecs = evecs.T``, before ``evecs D evecsᵀ``). ``sphere_fit`` and the SAR methods estimate the hard iron only (soft iron
taken as the identity). Every method's own ``calibrated_magnetic_field`` output applies its matrix to
``magnetic_field.reshape(3, -1)`` of an ``N x 3`` array, which interleaves the axes of different readings;
the spread of that output is recorded (``own_output_spread``) beside the estimates, and the bench applies the
estimates itself.
"""

from __future__ import annotations

import json
import pickle
import sys
import tempfile
import time
import traceback
from importlib.metadata import version
from pathlib import Path

import numpy as np

try:  # the peer's environment; magexp's has no magyc and imports this file for METHODS only
    import magyc
except ModuleNotFoundError as missing:
    if missing.name != "magyc":  # magyc is there, one of its own dependencies is not: a broken environment
        raise
    magyc = None

FORMAT = "magexp-peer-exchange v1"

#: MAGYC's methods: name -> (what it needs, what its returns are). ``hsi``: (hard iron, soft iron, calibrated);
#: ``hsiw``: (hard iron, soft iron, gyro bias, calibrated, ...); ``hi``: (hard iron, calibrated, ...)
METHODS = {
    "magyc_ls": ("gyro", "hsi"),
    "magyc_nls": ("gyro", "hsiw"),
    "magyc_bfg": ("gyro", "hsiw"),
    "magyc_ifg": ("gyro", "hsiw"),
    "ellipsoid_fit": ("mag", "hsi"),
    "sphere_fit": ("mag", "hi"),
    "twostep_hsi": ("reference", "hsi"),
    "sar_ls": ("gyro", "hi"),
    "sar_kf": ("gyro", "hi"),
    "sar_aid": ("gyro", "hi"),
}
#: the MAGYC paper's Monte Carlo simulation (sec. V; the magyc repository's ``docs/simulated_data.md``): 10 Hz
#: (6,000 readings = 600 s), 10 mG magnetometer and 10 mrad/s gyroscope noise. Its motion levels: WAM = ``high``,
#: MAM = ``mid``, LAM = ``low`` (the generator also makes ``tiny`` and ``cross``)
PAPER = {"frequency": 10.0, "mag_noise_G": 0.01, "gyro_noise_rad_s": 0.01}
#: the methods whose ``soft_iron`` is the correction ``SI^-1`` (module docstring)
CORRECTION = ("ellipsoid_fit",)


def need_magyc() -> None:
    """Stop, in one line, where magyc is not installed (this file runs in the peer's environment, ``make peers``)."""
    if magyc is None:
        raise SystemExit("magyc_side.py runs in the peer's environment (.peers/venv, make peers): magyc is not "
                         "installed in this one")


def _spread(vectors) -> float:
    """``std / mean`` of the vectors' norms (NaN for none): the peer's side of :func:`.measures.field_spread`."""
    mags = np.linalg.norm(np.asarray(vectors, float).reshape(-1, 3), axis=1)
    return float(mags.std() / mags.mean()) if mags.size else float("nan")


def prepare(data: dict, side: dict) -> dict:
    """The peer's own preprocessing, as its example notebook (``example/20241107_sim_calibration.ipynb``) does
    before every method: a Savitzky-Golay filter of ``savgol_window`` samples and order ``savgol_order`` on the
    magnetometer and the gyroscope (none when the sidecar sets no window).
    """
    window = side.get("savgol_window")
    if not window:
        return data
    # lazy: 0.54 s CPU to import in magexp's environment (min of 3, after magexp.perf.peers.bench's imports),
    # which imports this file for METHODS only
    from scipy.signal import savgol_filter

    order = int(side.get("savgol_order", 2))
    return {"t": data["t"], "mag": savgol_filter(data["mag"], int(window), order, axis=0),
            "gyro": savgol_filter(data["gyro"], int(window), order, axis=0)}


def call(method: str, data, side: dict) -> dict:
    """One MAGYC method on ``data`` (``t``, ``mag``, ``gyro``) -> its estimates as plain lists. MAGYC-BFG and
    -IFG take the sidecar's ``measurements_window`` (their example notebook: the sample rate in Hz).
    """
    needs, returns = METHODS[method]
    mag, gyro, t = data["mag"], data["gyro"], data["t"]
    fun = getattr(magyc, method)
    start = time.perf_counter()
    if method in ("magyc_bfg", "magyc_ifg") and side.get("measurements_window"):
        out = fun(mag, gyro, t, int(side["measurements_window"]))
    elif needs == "gyro":
        out = fun(mag, gyro, t)
    elif needs == "reference":  # TWOSTEP needs the field's magnitude (only its norm enters) and the noise
        out = fun(mag, np.array([0.0, 0.0, float(side["reference_total"])]),
                  measurement_noise_std=float(side["mag_noise_std"]))
    else:
        out = fun(mag)
    seconds = time.perf_counter() - start
    hard = np.asarray(out[0], float).ravel()
    soft = np.asarray(out[1], float).reshape(3, 3) if returns in ("hsi", "hsiw") else None
    bias = np.asarray(out[2], float).ravel() if returns == "hsiw" else None
    own = out[3] if returns == "hsiw" else (out[2] if returns == "hsi" else out[1])
    return {"method": method, "hard_iron": hard.tolist(), "soft_iron": None if soft is None else soft.tolist(),
            "gyro_bias": None if bias is None else bias.tolist(),
            "convention": "correction" if method in CORRECTION else "distortion",
            "seconds": seconds, "own_output_spread": _spread(own), "error": None}


def run(path_in: str, path_out: str) -> None:
    """Every method of the sidecar's ``methods`` on ``path_in``; the estimates to ``path_out``."""
    need_magyc()
    side = json.loads(Path(path_in).with_suffix(".json").read_text())
    if side.get("format") != FORMAT:
        raise SystemExit(f"{path_in}: format {side.get('format')!r} is not allowed: expected {FORMAT!r}")
    with np.load(path_in, allow_pickle=False) as npz:
        data = prepare({k: np.asarray(npz[k], float) for k in ("t", "mag", "gyro")}, side)
    results = []
    for method in side.get("methods") or list(METHODS):
        if method not in METHODS:
            results.append({"method": method, "error": f"unknown method (known: {', '.join(METHODS)})"})
            continue
        try:
            results.append(call(method, data, side))
        except Exception as exc:  # a peer method that fails is a result, not a crash of the bench
            results.append({"method": method, "error": f"{type(exc).__name__}: {str(exc).splitlines()[0][:200]}",
                            "trace": traceback.format_exc(limit=2)[-400:]})
    Path(path_out).write_text(json.dumps({"format": FORMAT, "peer": "magyc", "version": version("magyc"),
                                          "numpy": np.__version__, "results": results}, indent=1))


def synth(out_dir: str, seed: str, nsamples: str) -> None:
    """MAGYC's generator, one simulation per motion level, exported as neutral datasets with the truth."""
    need_magyc()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    np.random.seed(int(seed))  # the generator draws from numpy's global generator
    freq, mag_noise, gyro_noise = PAPER["frequency"], PAPER["mag_noise_G"], PAPER["gyro_noise_rad_s"]
    with tempfile.TemporaryDirectory() as tmp:
        magyc.create_synthetic_dataset(Path(tmp), niter=1, nsamples=int(nsamples), frequency=freq,
                                       mag_noise_G=mag_noise, gyro_noise_rad_s=gyro_noise)
        (pkl,) = Path(tmp).glob("*.pkl")
        with open(pkl, "rb") as fh:  # the file the generator has just written in a private folder
            levels = pickle.load(fh)
    for level, d in levels.items():
        stem = out / f"magyc_{level}_s{seed}"
        np.savez(stem.with_suffix(".npz"), t=d["t"][0].ravel(), mag=d["mmt"][0], gyro=d["wmt"][0],
                 truth_soft_iron=d["si"][0], truth_hard_iron=d["hi"][0].ravel(), truth_gyro_bias=d["wb"][0].ravel(),
                 truth_field=d["m0"][0].ravel(), truth_field_start=d["m"][0][0])
        side = {"format": FORMAT, "name": f"magyc_{level}", "kind": "magyc_synthetic", "seed": int(seed),
                "source": "magyc.create_synthetic_dataset (magyc 1.0.0), motion level " + level,
                "mag_unit": "G", "gyro_unit": "rad/s", "time_unit": "s", "mag_noise_std": mag_noise,
                "gyro_noise_std": gyro_noise, "frequency_hz": freq,
                "axes": "magnetometer and gyroscope in one body frame (the generator's)",
                "alignment": "gyro[k]: the rate over [t[k-1], t[k]] (the generator's log of the relative rotation / dt)"}
        stem.with_suffix(".json").write_text(json.dumps(side, indent=1))


if __name__ == "__main__":
    args = sys.argv[1:]
    if len(args) == 4 and args[0] == "synth":
        synth(*args[1:])
    elif args and len(args) % 2 == 0 and args[0] != "synth":
        for path_in, path_out in zip(args[::2], args[1::2]):  # one process: jax compiles once
            run(path_in, path_out)
    else:
        print("usage: magyc_side.py IN.npz OUT.json [IN.npz OUT.json ...] | synth OUT_DIR SEED NSAMPLES", file=sys.stderr)
        raise SystemExit(2)
