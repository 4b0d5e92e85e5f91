"""The datasets of the bench, as neutral files (:mod:`.exchange`), the same for magexp and the peer.

Three kinds:

* ``magyc_synthetic``: MAGYC's own generator (:func:`.exchange.synthesise`), one simulation per motion level
  and seed, with its truth (the peer's conventions: gauss, rad/s, ``m = SI m_true + HI``);
* ``yuan_stream``: Yuan 2018's simulated scenarios (``conf/scenario/yuan2018_*.yaml``) at their full sample
  rate (100 Hz, every sample a magnetometer reading with its gyro rate), drawn by :func:`yuan_stream` from the
  scenario's own trajectory, gyro model, noise and truth. Yuan's 30 readings per run are too sparse for a method
  that differentiates the magnetometer (36° between readings), so both sides get the stream;
* ``recording``: the HMC5883L + MPU6050 recordings (``../shared/data``) through magexp's reader, with one axis
  map and one time alignment for everyone (:func:`recording`).

Time alignment (every kind): the magnetometer's times are the grid; ``gyro[k]`` is the gyroscope's rate
averaged over ``[t[k-1], t[k]]`` with each gyro sample held until the next (:func:`rates_at`), the interval of
the backward difference the peer pairs it with. A constant bias passes through the average unchanged. The
HMC5883L and MPU6050 streams' timestamps are used as recorded (their first samples are 4 ms apart; no offset
is applied: none is stated by the authors) and, as a second variant, *retimed*: they are arrival times of buffered
bursts, and each stream gets a constant-rate clock fitted to them (:func:`recording`).
"""

from __future__ import annotations

import numpy as np

from magexp.core.geometry import integrate_rates, merged_steps
from magexp.core.recordings import load_recording
from magexp.core.seeding import run_generators
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA
from magexp.perf.peers.exchange import FORMAT, NeutralDataset
from magexp.run.compose import compose_config
from magexp.run.runner import build
from magexp.scenarios.search import centroid_radius

#: the HMC5883L + MPU6050 sequences of the bench (``hmc5883l_<sequence>_{mag,imu}.csv``)
SEQUENCES = ("full-sphere", "rotate-ccw-around-x", "rotate-ccw-around-y", "rotate-ccw-around-z",
             "roll-and-tilt-at-45-90")
REST = "unmoved-10min"
#: axis maps onto the gyroscope's axes (:func:`magexp.core.geometry.axis_map`): ``aligned`` turns the magnetometer's
#: x and y by 180° (``-x,-y,z``; magexp's gyro-aided fit of the recording finds S11 + S22 near -2, claim
#: ``axes_flipped`` of ``real_table7``), ``recorded`` keeps both as recorded, ``authors`` flips the gyroscope's
#: x (the authors' note, ``-x,y,z``). The peer's symmetric soft iron cannot absorb a rotation between the two
#: sensors; magexp's full ``S`` can.
AXIS_MAPS = {"aligned": ("-x,-y,z", "x,y,z"), "recorded": ("x,y,z", "x,y,z"), "authors": ("x,y,z", "-x,y,z")}
#: per-axis noise of the HMC5883L at rest (gauss; the data folder's README), given to TWOSTEP
HMC_NOISE_G = 0.0015
#: the Yuan scenarios of the bench: turns about X, Y, Z; X, Y; partial turns; Z only; changing field; gyro drift
YUAN_SCENARIOS = ("yuan2018_mode1", "yuan2018_mode2", "yuan2018_mode3", "yuan2018_mode4",
                  "yuan2018_changing_field", "yuan2018_drift")


def rates_at(gyro_times: np.ndarray, rates: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The gyro rate averaged over each interval ``[at[k-1], at[k]]`` (each sample held until the next),
    ``(len(at), 3)``; the first row repeats the second.

    .. math:: \\bar\\omega_k = \\frac{1}{t_k - t_{k-1}} \\int_{t_{k-1}}^{t_k} \\omega(t)\\,dt
    """
    r, dt, index = merged_steps(gyro_times, rates, at)
    cum = np.concatenate([np.zeros((1, 3)), np.cumsum(r * dt[:, None], axis=0)])[index]
    mean = np.diff(cum, axis=0) / np.diff(at)[:, None]
    return np.concatenate([mean[:1], mean])


def side(name: str, kind: str, *, seed, mag_unit: str, mag_noise_std: float, reference_total: float, axes: str,
         alignment: str, **more) -> dict:
    """A sidecar (:mod:`.exchange`)."""
    return {"format": FORMAT, "name": name, "kind": kind, "seed": seed, "mag_unit": mag_unit, "gyro_unit": "rad/s",
            "time_unit": "s", "mag_noise_std": float(mag_noise_std), "reference_total": float(reference_total),
            "axes": axes, "alignment": alignment, **more}


def with_reference(ds: NeutralDataset) -> NeutralDataset:
    """``reference_total``: the radius of the sphere fitted to the readings (no method gets the truth's)."""
    ds.side["reference_total"] = centroid_radius(ds.mag)
    return ds


def yuan_stream(scenario: str, seed: int) -> NeutralDataset:
    """Yuan's scenario ``scenario`` at its full sample rate, from the scenario's own components.

    Every sample ``k`` of the trajectory is a reading ``B_k = S C_k H_k + b + ε_k`` (:mod:`magexp.scenarios.yuan`,
    eq 1) and the gyro rate ``ω_k + drift + noise`` held over ``[t_k, t_{k+1}]`` (:class:`~magexp.scenarios.motion.Gyro`);
    the truth is ``D = S``, ``h = b``, the gyro bias the drift vector.
    """
    cfg = compose_config([f"scenario={scenario}"])
    scen = build(cfg.scenario, "scenario")
    rng, _ = run_generators(int(seed), f"peers/{scenario}")  # the bench's own stream of the scenario
    rates = scen.trajectory.rates()
    dt = scen.trajectory.dt
    n = len(rates)
    true_bn = integrate_rates(rates, dt)[:-1]
    measured = scen.gyro.measure(rates, rng=rng)
    ramp = np.linspace(scen.field_scale[0], scen.field_scale[1], n)
    body = np.einsum("nji,nj->ni", true_bn, ramp[:, None] * scen.field)  # C_k H_k, C = (body -> nav)^T
    readings = body @ scen.s.T + scen.b + scen.noise.sample(body.shape, rng=rng)
    gyro = np.concatenate([measured[:1], measured[:-1]])  # rate over [t_{k-1}, t_k]
    meta = side(scenario, "yuan_stream", seed=int(seed), mag_unit="mG", mag_noise_std=scen.noise.std,
                reference_total=centroid_radius(readings),
                axes="magnetometer and gyroscope in one body frame (Yuan's simulation)",
                alignment="gyro[k]: the simulated gyro sample held over [t[k-1], t[k]]",
                source=f"conf/scenario/{scenario}.yaml at {1 / dt:g} Hz, {n} readings")
    truth = {"truth_soft_iron": scen.s, "truth_hard_iron": scen.b, "truth_gyro_bias": scen.gyro.drift,
             "truth_field": scen.field * scen.field_scale[0], "truth_field_start": body[0]}
    return NeutralDataset(np.arange(n) * dt, readings, gyro, meta, truth)


def constant_rate(times: np.ndarray) -> np.ndarray:
    """A constant-rate clock fitted to ``times`` (least squares of time on sample index)."""
    k = np.arange(len(times))
    return np.polyval(np.polyfit(k, times, 1), k)


def recording(sequence: str, axis_map: str = "aligned", *, retime: bool = False) -> NeutralDataset:
    """The HMC5883L + MPU6050 ``sequence`` with the axis map ``axis_map`` of :data:`AXIS_MAPS` (gauss, rad/s).

    ``retime``: both streams' timestamps replaced by :func:`constant_rate` clocks (name suffix ``_retimed``). The
    recorded timestamps are arrival times of buffered bursts (median spacing about 3 ms, gaps up to 250 ms, for
    sensors sampling at 77 and 99 Hz): a method that differentiates the readings over their timestamps sees
    nonsense rates; one that integrates the gyroscope between them sees attitudes off by up to one gap.
    """
    if axis_map not in AXIS_MAPS:
        raise MagexpError(f"axis_map={axis_map!r} is not allowed: choose one of {', '.join(AXIS_MAPS)}")
    mag_axes, gyro_axes = AXIS_MAPS[axis_map]
    path = SHARED_DATA / f"hmc5883l_{sequence}"
    if not path.with_name(path.name + "_mag.csv").exists():
        raise MagexpError(f"recording {sequence!r} is not allowed: {path}_mag.csv does not exist "
                          "(set MAGEXP_DATA to the folder of the recordings)")
    rec = load_recording(path, mag_axes=mag_axes, gyro_axes=gyro_axes)
    t = rec.reading_times()
    gyro_t, rates = rec.gyro_rates()
    if retime:
        t, gyro_t = constant_rate(t), constant_rate(gyro_t)
    clock = ("each stream's timestamps replaced by a constant-rate clock fitted to them" if retime
             else "timestamps as recorded")
    meta = side(f"hmc5883l_{sequence}" + ("_retimed" if retime else ""), "recording", seed=0, mag_unit=rec.unit, mag_noise_std=HMC_NOISE_G,
                reference_total=centroid_radius(rec.readings), axis_map=axis_map, mag_axes=mag_axes,
                gyro_axes=gyro_axes, axes=f"magnetometer {mag_axes}, gyroscope {gyro_axes} (magexp.core.geometry.axis_map)",
                alignment="gyro[k]: the MPU6050's rate averaged over [t[k-1], t[k]] (samples held until the next), "
                          + clock, saturated_fraction=float(np.mean(np.abs(np.rad2deg(rates)) >= 249.0)))
    return NeutralDataset(t - t[0], rec.readings, rates_at(gyro_t - t[0], rates, t - t[0]), meta)


def rest_bias(axis_map: str = "aligned") -> np.ndarray:
    """The mean rate (rad/s) of the 10-minute rest recording in the gyroscope axes of ``axis_map``."""
    mag_axes, gyro_axes = AXIS_MAPS[axis_map]
    rec = load_recording(SHARED_DATA / f"hmc5883l_{REST}", mag_axes=mag_axes, gyro_axes=gyro_axes)
    return rec.gyro_rates()[1].mean(axis=0)
