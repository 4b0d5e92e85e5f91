"""magexp beside a peer: the gyro-aided calibration of MAGYC (Rodríguez-Martínez et al. 2024, the ``magyc``
package, MIT) run on the same data as magexp's estimators, measured the same way (issue 22).

The peer lives in its own environment (``make peers``: ``.peers/venv`` from ``requirements-peers.lock``;
magyc pins numpy < 2 and jax < 0.5 and needs gtsam). The two sides never import each other: magexp writes
each dataset to a neutral file (:mod:`.exchange`), runs :mod:`.magyc_side` in the peer's interpreter as a
subprocess and reads its estimates back.

* :mod:`.exchange`: the neutral dataset (``.npz`` + JSON sidecar), the peer's results, the subprocess;
* :mod:`.data`: the datasets: MAGYC's own generator, Yuan 2018's simulated scenarios as full-rate streams,
  the HMC5883L + MPU6050 recordings with one axis map and one time alignment for everyone;
* :mod:`.magexp_side`: magexp's applicable estimators on a neutral dataset;
* :mod:`.measures`: the measures both sides get (parameter errors against the truth, spreads, gyro bias);
* :mod:`.bench`: ``python -m magexp.perf.peers.bench --out DIR``: the long-format CSV, the figure, the text.

Imports: numpy, and magexp's core (recordings, geometry, problems, estimators, scenarios); nothing imports it.
:mod:`.magyc_side` imports neither magexp nor anything but numpy and magyc.
"""
