"""magexp's side of the bench: its applicable estimators on a neutral dataset (:mod:`.exchange`).

Every method returns an :class:`.exchange.Estimate` in the peer's form, ``m = D m_true + h`` (``D = W^-1``, ``h = o``
of magexp's ``W (r - o)``), the gyro bias in rad/s where the method estimates one, and its wall seconds.

* ``gyro`` objective (:class:`magexp.problems.gyro.GyroAidedCalibration`, Yuan 2018 eq 8 with the field direction
  and the gyro bias estimated, 17 parameters): ``lm`` (from the problem's two-stage start) and, when asked,
  ``rdpso`` (Yuan's swarm, Table 1 budget). The fit takes ``n_fit`` readings evenly spaced over the dataset
  (:data:`N_FIT`, as ``real_table7``; the cost is a sum over readings, and a few hundred readings of a turning
  sensor fix 17 parameters; at most :data:`LM_NFEV` evaluations, the peer's own budget), with the gyroscope preintegrated over *every* interval between them
  (:func:`magexp.core.geometry.preintegrate`): it uses the whole gyro stream and the readings it is given. The box is
  the recording scenarios' ``signed`` box from the data (:func:`magexp.scenarios.search.search_box`);
* ``scalar`` objective (a total field, no gyroscope): ``ellipsoid`` and ``twostep`` on every reading.

On MAGYC's synthetic data the bench runs both sides on the same readings and the same budget, both ways: every
reading to both, and both on the ``n_fit`` readings of :func:`subset` (the gyroscope between them given to both as
one mean rate per interval, exactly the preintegrated rotation).

The field magnitude every method is given is the sidecar's ``reference_total`` (the radius of the sphere fitted
to the readings, :func:`.data.with_reference`): the gyro-aided fit and the peer's gyro methods cannot tell the
field's magnitude from the scale of ``D``, and the bench compares ``D`` up to scale (:mod:`.measures`).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from magexp.run.named import estimator_named
from magexp.core.dataset import Dataset
from magexp.errors import MagexpError
from magexp.core.geometry import preintegrate
from magexp.perf.peers.exchange import Estimate, NeutralDataset
from magexp.problems import make_problem
from magexp.scenarios.search import search_box
from magexp.core.seeding import run_generators

#: readings of the gyro-aided fit (evenly spaced over the dataset; a documented default, ``--n-fit``)
N_FIT = 300
#: evaluations of the gyro-aided ``lm``: the peer's budget. magyc 1.0.0's MAGYC-LS and -NLS call
#: ``scipy.optimize.least_squares(..., max_nfev=1000)`` and MAGYC-BFG runs gtsam with ``max_iter=1000``
#: (``magyc/methods/magyc.py``; MAGYC-IFG updates iSAM2 once per ten windows, with no iteration budget); magexp's ``lm`` config allows 2000, which take 100 s where turns about one axis
#: leave the problem unidentified
LM_NFEV = 1000
#: magexp's methods: name -> (objective, estimator config, overrides)
METHODS = {
    "magexp_lm_gyro": ("gyro", "lm", {"max_nfev": LM_NFEV}),
    "magexp_rdpso_gyro": ("gyro", "rdpso", {"boundary": "reflect"}),
    "magexp_ellipsoid": ("scalar", "ellipsoid", {}),
    "magexp_twostep": ("scalar", "twostep", {}),
}
#: ``fit_on`` of MAGYC's data on the readings of :func:`subset`, given to both sides (``all``: every reading to both)
SUBSET = "subset"
DEFAULT = ("magexp_lm_gyro", "magexp_ellipsoid", "magexp_twostep")


def fit_indices(n: int, n_fit: int = N_FIT) -> np.ndarray:
    """The indices of ``n_fit`` readings evenly spaced over ``n`` (all of them when ``n_fit >= n``)."""
    return np.unique(np.round(np.linspace(0, n - 1, min(n_fit, n))).astype(int))


def subset(ds: NeutralDataset, n_fit: int = N_FIT) -> NeutralDataset:
    """The readings of :func:`fit_indices` as a dataset both sides are given: the gyro rate at each reading is the
    mean rate over the interval since the previous one, ``log(ΔR) / Δt`` of the rotation preintegrated over every
    gyro sample between them (:func:`magexp.core.geometry.preintegrate`; the generator's own convention, a rate
    held over the interval that reproduces ``ΔR`` exactly); the first reading keeps its rate.
    """
    fit = fit_indices(len(ds.t), n_fit)
    delta, _ = preintegrate(ds.t[:-1], ds.gyro[1:], ds.t[fit])
    rates = Rotation.from_matrix(delta).as_rotvec() / np.diff(ds.t[fit])[:, None]
    gyro = np.vstack([ds.gyro[fit[0]], rates])
    side = dict(ds.side, subset=f"{len(fit)} of {len(ds.t)} readings, evenly spaced")
    return NeutralDataset(ds.t[fit], ds.mag[fit], gyro, side, dict(ds.truth))


def gyro_problem(ds: NeutralDataset, n_fit: int = N_FIT):
    """The gyro-aided problem on ``n_fit`` evenly spaced readings of ``ds`` (module docstring)."""
    fit = fit_indices(len(ds.t), n_fit)
    radius = float(ds.side["reference_total"])
    # gyro[k] is the rate over [t[k-1], t[k]]: held from t[k-1] on
    delta = preintegrate(ds.t[:-1], ds.gyro[1:], ds.t[fit])
    data = Dataset(readings=ds.mag[fit], reference_norm=np.full(len(fit), radius), unit=ds.side["mag_unit"],
                   meta={"scenario": ds.name}, extra={"preintegration": delta})
    box = search_box(data.readings, radius, forward=True, shape="signed", matrix_bound=3.0)
    return make_problem("gyro", data, box, bias_bound_deg_s=10.0)


def scalar_problem(ds: NeutralDataset):
    """The total-field problem on every reading of ``ds``."""
    radius = float(ds.side["reference_total"])
    data = Dataset(readings=ds.mag, reference_norm=np.full(len(ds.t), radius), unit=ds.side["mag_unit"],
                   noise_std=float(ds.side["mag_noise_std"]), meta={"scenario": ds.name})
    return make_problem("scalar", data, search_box(ds.mag, radius))


def fit(method: str, ds: NeutralDataset, *, seed: int = 0, n_fit: int = N_FIT) -> Estimate:
    """magexp's ``method`` of :data:`METHODS` on ``ds``."""
    objective, name, overrides = METHODS[method]
    estimator = estimator_named(name, **overrides)
    _, rng = run_generators(int(seed), f"peers/{ds.name}")
    start = time.perf_counter()
    problem = gyro_problem(ds, n_fit) if objective == "gyro" else scalar_problem(ds)
    try:
        result = estimator.fit(problem, rng=rng)
    except (MagexpError, np.linalg.LinAlgError) as exc:
        return Estimate(method, None, None, None, time.perf_counter() - start, str(exc).splitlines()[0])
    seconds = time.perf_counter() - start
    w, o = (a[0] for a in problem.unpack(result.x))
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(o))) or abs(np.linalg.det(w)) < 1e-300:
        return Estimate(method, None, None, None, seconds, "non-finite or singular calibration")
    bias = np.deg2rad(np.asarray(result.x[14:17], float)) if objective == "gyro" else None
    return Estimate(method, np.linalg.inv(w), np.asarray(o, float), bias, seconds)
