"""A recording with attitudes, simulated: what ``objective=vector`` needs and no shared recording has.

``python -m magexp.calibration.simulate attitudes.csv`` writes a ``magexp-recording v1`` file: readings of a
magnetometer turned through random attitudes, each with its ``heading, roll, trim`` (radians; Yan & Zhou
2022's eq 2, ``A = R_y(trim) R_x(roll) R_z(heading)``, navigation -> sensor) and the ambient field as
``# field:``. What a rig that knows its attitudes records (a gimbal, a turntable, motion capture); the
shared recordings have none with a field (the logs' attitudes come without one, the HMC5883L's gyroscope
carries the attitude only with a bias to fit: ``model=gyro``).

The model, in nT (:func:`simulate`)::

    r = W^-1 A F + o + n

with ``F`` the field of Yan & Zhou's mock-up (``data/yan2022_mockup.csv``, its ``# field:``), ``A`` drawn
with a uniform heading and trim and a roll uniform in ``[-90, 90]`` degrees, ``W^-1 = I + E``
(``E`` each entry normal with standard deviation :data:`DISTORTION`, a rotation included), the offset
``o`` normal with standard deviation :data:`OFFSET_NT` per axis and the noise ``n`` :data:`NOISE_NT` per
axis. Every draw comes from the data generator of ``--seed`` (:func:`magexp.core.seeding.run_generators`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from magexp.core.atomic import write_text
from magexp.core.readers.magexp_v1 import VERSION_LINE
from magexp.core.geometry import ship_attitude
from magexp.core.limits import refuse_over
from magexp.core.recordings import load_recording
from magexp.core.seeding import run_generators
from magexp.errors import MagexpError, check_positive_int, exit_code
from magexp.run.keys import check_seed
from magexp.paths import DATA

#: the standard deviation of each entry of ``E`` in ``W^-1 = I + E`` (soft iron and a misalignment)
DISTORTION = 0.03
#: the standard deviation of each axis of the offset (hard iron), nT
OFFSET_NT = 300.0
#: the standard deviation of the noise on each axis, nT
NOISE_NT = 20.0


def simulate(n: int, seed: int) -> tuple[str, np.ndarray, np.ndarray]:
    """The text of a simulated recording with attitudes (module docstring), and its true ``W`` and offset."""
    n = check_readings(n, "n")
    seed = check_seed(seed)
    rng, _ = run_generators(seed)
    field = load_recording(DATA / "yan2022_mockup.csv").field
    angles = np.column_stack([rng.uniform(0, 2 * np.pi, n), rng.uniform(-np.pi / 2, np.pi / 2, n),
                              rng.uniform(-np.pi, np.pi, n)])
    distortion = np.eye(3) + rng.normal(0, DISTORTION, (3, 3))
    offset = rng.normal(0, OFFSET_NT, 3)
    raw = (ship_attitude(*angles.T) @ field) @ distortion.T + offset + rng.normal(0, NOISE_NT, (n, 3))
    head = [VERSION_LINE, f"# source: magexp.calibration.simulate, {n} readings, seed {seed}", "# unit: nT",
            "# angles: rad", "# field: " + ", ".join(f"{v:g}" for v in field), "bx,by,bz,heading,roll,trim"]
    rows = "".join(",".join(f"{v:.10g}" for v in row) + "\n" for row in np.column_stack([raw, angles]))
    return "\n".join(head) + "\n" + rows, np.linalg.inv(distortion), offset


def command(argv: list[str]) -> None:
    """``python -m magexp.calibration.simulate PATH [--readings N] [--seed S]``: write the recording to ``PATH``
    (never over an existing file) and print where."""
    parser = argparse.ArgumentParser(prog="python -m magexp.calibration.simulate", description=__doc__.splitlines()[0])
    parser.add_argument("path", help="the recording to write (magexp-recording v1)")
    parser.add_argument("--readings", default=400, help="how many readings (default 400)")
    parser.add_argument("--seed", default=0, help="the seed of the draws (default 0)")
    args = parser.parse_args(argv)
    n = check_readings(_integer(args.readings), "--readings")
    seed = check_seed(_integer(args.seed), "--seed")
    path = Path(args.path)
    if path.exists():
        raise MagexpError(f"path {str(path)!r} is not allowed: it exists already (never overwritten), choose another")
    if not path.parent.is_dir():
        raise MagexpError(f"path {str(path)!r} is not allowed: its folder {str(path.parent)!r} does not exist")
    text, _, _ = simulate(n, seed)
    write_text(path, text)
    print(f"wrote {path}: {n} readings with heading, roll, trim and the field (seed {seed})")


def check_readings(n, name: str) -> int:
    """``n`` as an int: an integer >= 12 within the readings limit (``MAGEXP_MAX_READINGS``), else one line naming ``name``.
    """
    n = check_positive_int(n, name, minimum=12)
    refuse_over(n, "readings", f"{name}={n}", "it makes")
    return n


def _integer(text):
    """``text`` as an int where it spells one (else as given, for the check to name)."""
    return int(text) if str(text).strip().lstrip("-").isdigit() else text


def main(argv: list[str] | None = None) -> int:
    """Run :func:`command` as a process does (:func:`magexp.errors.exit_code`)."""
    return exit_code(command, sys.argv[1:] if argv is None else list(argv))


if __name__ == "__main__":
    sys.exit(main())
