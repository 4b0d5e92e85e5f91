"""Every advice a refusal of magexp calibrate gives names a key that works: each ``key=value`` it advises
is parsed from the message and run (issue 33, item 3: counts_nt, instance and max_rotation_deg exist)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from magexp.core.geometry import random_rotations, rot_z, ship_attitude
from tests.test_calibrate import write_recording
from tests.test_calibration_files import sphere_recording

#: ``key=value`` in a message, not the echo of a refused value (``key='x' is not allowed``)
ADVICE = re.compile(r"(?<![\w.=])([a-z_]+(?:\.[a-z_]+)*)=((?:<[^>]*>)|[^\s,;)]+)(?! is not allowed)")


def advised(message: str) -> list[str]:
    """The ``key=value`` overrides ``message`` advises, a ``<placeholder>`` given a number."""
    return [f"{key}={'100' if value.startswith('<') else value}" for key, value in ADVICE.findall(message)]


def rotated_vector_recording(path, degrees: float = 5.0, n: int = 200, seed: int = 4):
    """Attitudes and a field, readings ``W⁻¹ A f + o`` with ``W`` turning by ``degrees`` (a mounting error)."""
    rng = np.random.default_rng(seed)
    angles = np.column_stack([rng.uniform(0, 2 * np.pi, n), rng.uniform(-np.pi, np.pi, n), rng.uniform(-1.5, 1.5, n)])
    field = np.array([20.0, 3.0, 45.0])
    q = random_rotations(1, rng=rng)[0]
    w = rot_z(np.deg2rad(degrees)) @ q @ np.diag([1.05, 0.97, 1.01]) @ q.T
    b = np.einsum("nij,j->ni", ship_attitude(*angles.T), field)
    readings = b @ np.linalg.inv(w).T + np.array([3.0, -2.0, 5.0])
    return write_recording(path, readings, meta=["# unit: uT", "# angles: rad", "# field: 20, 3, 45"],
                           extra={"heading": angles[:, 0], "roll": angles[:, 1], "trim": angles[:, 2]})


def stretched_recording(path):
    """A full sphere stretched 3.5 times along one axis: W's anisotropy fails the gate (3.0)."""
    rng = np.random.default_rng(8)
    d = rng.standard_normal((300, 3))
    d = 30 * d / np.linalg.norm(d, axis=1, keepdims=True)
    return write_recording(path, d * [3.5, 1.0, 1.0] + [5, 5, 5], meta=["# unit: uT"])


CASES = {  # name: (recording maker, arguments, the key the refusal must advise)
    "rotation_px4": (rotated_vector_recording, ["objective=vector", "estimator=lm", "export=px4"], "max_rotation_deg"),
    "rotation_ardupilot": (rotated_vector_recording, ["objective=vector", "estimator=lm", "export=ardupilot"],
                           "max_rotation_deg"),
    "counts": (lambda p: sphere_recording(p, unit="counts"), ["export=ardupilot", "instance=1"], "counts_nt"),
    "gate": (stretched_recording, ["model=full"], "accept"),
}


@pytest.mark.parametrize("case", CASES)
def test_each_advised_key_works(tmp_path, cli, case):
    make, args, key = CASES[case]
    path = make(tmp_path / f"{case}.csv")
    run = lambda *extra: cli("calibrate", f"data.path={path}", f"out={tmp_path / 'out'}", *args, *extra,  # noqa: E731
                             cwd=tmp_path)
    proc = run()
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    advice = advised(proc.stderr)
    assert any(a.startswith(f"{key}=") for a in advice), (advice, proc.stderr)
    print(f"{case}: {proc.stderr.strip()[:160]}... -> {advice}")
    for override in advice:
        done = run(override)
        assert done.returncode == 0, (override, done.stderr)
        assert not any(p.name.startswith(".") for p in (tmp_path / "out").iterdir())
        for p in (tmp_path / "out").iterdir():
            p.unlink()


def test_the_instance_names_the_exported_slot(tmp_path, cli):
    path = sphere_recording(tmp_path / "mine.csv")
    for target, instance, name in (("ardupilot", 2, "COMPASS_OFS3_X"), ("px4", 3, "CAL_MAG3_XOFF")):
        out = tmp_path / target
        proc = cli("calibrate", f"data.path={path}", f"out={out}", f"export={target}", f"instance={instance}",
                   cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert name in next(p for p in out.iterdir() if p.name.startswith("magexp_")).read_text()
    proc = cli("calibrate", f"data.path={path}", f"out={tmp_path / 'x'}", "export=ardupilot", "instance=3",
               cwd=tmp_path)
    assert proc.returncode == 2 and "instance=3 is not allowed for ardupilot" in proc.stderr
    counts = sphere_recording(tmp_path / "counts.csv", unit="counts")
    for bad, message in (("max_rotation_deg=abc", "max_rotation_deg='abc' is not allowed"),
                         ("counts_nt=-2", "counts_nt=-2"), ("instance=-1", "instance=-1 is not allowed")):
        proc = cli("calibrate", f"data.path={counts}", f"out={tmp_path / 'y'}", "export=px4", "counts_nt=10", bad,
                   cwd=tmp_path)
        assert proc.returncode == 2 and message in proc.stderr and proc.stderr.count("\n") == 1, (bad, proc.stderr)
        assert not (tmp_path / "y").exists()
