"""The neutral files between magexp and the peer, and the peer's subprocess.

A dataset is two files with one stem:

``<stem>.npz`` (read with ``allow_pickle=False``: nothing read from disk can run code)
    ``t`` (N,) seconds; ``mag`` (N, 3) magnetometer readings in ``mag_unit``; ``gyro`` (N, 3) angular rate in
    rad/s *at the magnetometer's times*: ``gyro[k]`` is the rate over ``[t[k-1], t[k]]`` (the interval that the
    backward difference ``(m[k] - m[k-1]) / (t[k] - t[k-1])`` spans; ``gyro[0]`` repeats ``gyro[1]``); both in the
    one body frame the sidecar's ``axes`` names. Simulations add the truth: ``truth_soft_iron`` (3, 3) and
    ``truth_hard_iron`` (3,) of ``m = D m_true + h``, ``truth_gyro_bias`` (3,) rad/s, ``truth_field`` (3,) and
    ``truth_field_start`` (3,), the noise-free field in the body frame at ``t[0]``.
``<stem>.json``
    ``format`` (:data:`FORMAT`), ``name``, ``kind``, ``seed``, ``mag_unit``, ``gyro_unit`` (``rad/s``),
    ``time_unit`` (``s``), ``mag_noise_std``, ``reference_total`` (the field magnitude every method that needs
    one is given), ``axes`` and ``alignment`` (in words), ``methods`` (the peer's methods to run).

The peer's answer (``<out>.json``): ``{"format", "peer", "version", "results": [{"method", "soft_iron",
"hard_iron", "gyro_bias", "convention", "seconds", "own_output_spread", "error"}]}`` (:mod:`.magyc_side`), read into
:class:`Estimate` objects, the form in which both sides' answers are measured (:mod:`.measures`).
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from magexp.errors import MagexpError
from magexp.paths import ROOT

FORMAT = "magexp-peer-exchange v1"
#: the peer's interpreter (``make peers``); ``MAGEXP_PEERS`` names another venv
PEER_VENV = Path(os.environ.get("MAGEXP_PEERS", ROOT / ".peers" / "venv"))
PEER_SCRIPT = Path(__file__).with_name("magyc_side.py")
ARRAYS = ("t", "mag", "gyro")
TRUTH = ("truth_soft_iron", "truth_hard_iron", "truth_gyro_bias", "truth_field", "truth_field_start")


@dataclass
class NeutralDataset:
    """One dataset as both sides see it (module docstring)."""

    t: np.ndarray
    mag: np.ndarray
    gyro: np.ndarray
    side: dict
    truth: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The dataset's name, from its sidecar."""
        return str(self.side["name"])

    def part(self, index, suffix: str) -> "NeutralDataset":
        """The readings ``index`` (a contiguous slice: the gyro rates stay those of each reading's interval)."""
        side = dict(self.side, name=f"{self.side['name']}{suffix}")
        return NeutralDataset(self.t[index], self.mag[index], self.gyro[index], side, dict(self.truth))


def check(ds: NeutralDataset) -> NeutralDataset:
    """One line naming what is wrong with a dataset, else the dataset."""
    n = len(ds.t)
    if ds.side.get("format") != FORMAT:
        raise MagexpError(f"{ds.side.get('name', '?')}: format={ds.side.get('format')!r} is not allowed: "
                          f"expected {FORMAT!r}")
    for key in ("mag", "gyro"):
        arr = getattr(ds, key)
        if arr.shape != (n, 3) or not np.all(np.isfinite(arr)):
            raise MagexpError(f"{ds.name}: {key} of shape {arr.shape} is not allowed: it must be ({n}, 3) finite numbers")
    if n < 12 or not np.all(np.diff(ds.t) > 0):
        raise MagexpError(f"{ds.name}: t is not allowed: it must hold at least 12 increasing times")
    return ds


def write(ds: NeutralDataset, stem: Path) -> Path:
    """``<stem>.npz`` and ``<stem>.json``; returns the ``.npz`` path."""
    check(ds)
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"t": ds.t, "mag": ds.mag, "gyro": ds.gyro, **{k: np.asarray(v, float) for k, v in ds.truth.items()}}
    np.savez(stem.with_suffix(".npz"), **arrays)
    stem.with_suffix(".json").write_text(json.dumps(ds.side, indent=1, sort_keys=True))
    return stem.with_suffix(".npz")


def read(path: Path) -> NeutralDataset:
    """The dataset of ``<stem>.npz`` and its sidecar."""
    path = Path(path)
    side = json.loads(path.with_suffix(".json").read_text())
    with np.load(path, allow_pickle=False) as npz:
        arrays = {k: np.asarray(npz[k], float) for k in npz.files}
    missing = [k for k in ARRAYS if k not in arrays]
    if missing:
        raise MagexpError(f"{path}: arrays {missing} are missing: a neutral dataset holds {', '.join(ARRAYS)}")
    return check(NeutralDataset(arrays["t"], arrays["mag"], arrays["gyro"], side,
                                {k: arrays[k] for k in TRUTH if k in arrays}))


def digest(ds: NeutralDataset) -> str:
    """What the peer's answer depends on: the arrays it reads and the methods asked for (sha256)."""
    h = hashlib.sha256()
    for arr in (ds.t, ds.mag, ds.gyro):
        h.update(np.ascontiguousarray(arr, float).tobytes())
    recipe = [ds.side[k] for k in ("savgol_window", "savgol_order", "measurements_window") if ds.side.get(k)]
    h.update(json.dumps([ds.side.get("methods"), ds.side.get("reference_total"), ds.side.get("mag_noise_std"),
                         *recipe]).encode())
    return h.hexdigest()


def available() -> str | None:
    """None when the peer's environment is there, else the one line saying why not."""
    python = PEER_VENV / "bin" / "python"
    if not (PEER_VENV / ".installed").exists() or not python.exists():
        return f"MAGYC's environment {PEER_VENV} is absent (make peers builds it): the peer is skipped"
    return None


def _peer(args: list[str], what: str, timeout: float) -> None:
    """Run :mod:`.magyc_side` with ``args`` in the peer's interpreter, on one thread; one line if it fails."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    env.update({"JAX_PLATFORMS": "cpu", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"})
    proc = subprocess.run([str(PEER_VENV / "bin" / "python"), str(PEER_SCRIPT), *args], capture_output=True,
                          text=True, timeout=timeout, env=env)
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise MagexpError(f"the peer failed on {what} (exit {proc.returncode}): {tail}")


def read_answer(out: Path) -> dict:
    """The peer's answer in ``out`` (module docstring)."""
    answer = json.loads(Path(out).read_text())
    if answer.get("format") != FORMAT:
        raise MagexpError(f"{out}: format={answer.get('format')!r} is not allowed: expected {FORMAT!r}")
    return answer


def run_peer(pairs: list[tuple[Path, Path]], *, timeout: float = 3600.0) -> list[dict]:
    """Run :mod:`.magyc_side` on every ``(npz, out)`` of ``pairs`` in one process of the peer's interpreter;
    its answers (module docstring), in order.
    """
    _peer([str(p) for pair in pairs for p in pair], f"{len(pairs)} datasets", timeout)
    return [read_answer(out) for _, out in pairs]


def synthesise(out_dir: Path, seed: int, nsamples: int, *, timeout: float = 600.0) -> list[Path]:
    """MAGYC's own generator in the peer's environment (:func:`.magyc_side.synth`): the ``.npz`` files made."""
    _peer(["synth", str(out_dir), str(int(seed)), str(int(nsamples))], f"its generator (seed {seed})", timeout)
    return sorted(Path(out_dir).glob(f"magyc_*_s{int(seed)}.npz"))


@dataclass
class Estimate:
    """One method's answer on one dataset, of either side, in the peer's form ``m = D m_true + h``: ``D`` the soft
    iron, ``h`` the hard iron (:mod:`.magexp_side` maps magexp's ``W (r - o)`` onto it)."""

    method: str
    soft_iron: np.ndarray | None  # D of m = D m_true + h; None: taken as the identity
    hard_iron: np.ndarray | None
    gyro_bias: np.ndarray | None  # rad/s
    seconds: float
    error: str | None = None
    own_output_spread: float = float("nan")

    @classmethod
    def from_peer(cls, result: dict) -> "Estimate":
        """The peer's JSON result (:mod:`.magyc_side`), its ``correction`` matrices inverted."""
        if result.get("error"):
            return cls(result["method"], None, None, None, float("nan"), result["error"])
        soft = None if result.get("soft_iron") is None else np.asarray(result["soft_iron"], float)
        if soft is not None and result.get("convention") == "correction":
            soft = np.linalg.inv(soft)
        bias = result.get("gyro_bias")
        values = [v for v in (result.get("soft_iron"), result["hard_iron"], bias) if v is not None]
        if not all(np.all(np.isfinite(np.asarray(v, float))) for v in values):
            return cls(result["method"], None, None, None, float(result["seconds"]), "non-finite estimate")
        return cls(result["method"], soft, np.asarray(result["hard_iron"], float),
                   None if bias is None else np.asarray(bias, float), float(result["seconds"]),
                   own_output_spread=float(result.get("own_output_spread", float("nan"))))
