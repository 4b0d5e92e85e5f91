"""What ``model=auto`` costs beside ``model=full`` where a gyroscope is usable, and what it chooses (issue 40).

For every shared recording with a gyroscope (the x-io IMU, the HMC5883L two-stream recordings, the PX4 ULogs, the
ArduPilot DataFlash log), ``magexp calibrate data.path=<recording> model=auto`` and ``model=full`` run as
commands, alternately, ``--repeats`` times each in one run, and the CPU time of each command (user + system,
``resource.getrusage(RUSAGE_CHILDREN)``: the interpreter, the imports and composing the config included) is
set side by side: the ratio of their medians is the cost of ``auto``, on the same machine at the same time.
A refused calibration is measured as it is: its refusal is the work a user waits for. Beside it, what ``auto``
chose, with every candidate's held-out spread (from the API with ``accept=True``, so that a recording the gate
refuses still shows the choice), and the command's outcome (accepted, or the first words of its refusal).

Each command runs with one BLAS thread, as every magexp command does (:mod:`magexp.run.threads`). Nothing is
written but the commands' output folders, in a temporary folder removed afterwards.

Usage: ``python -m magexp.perf.autocost [--repeats 3] [--only NAME ...]``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

#: the shared recordings with a gyroscope (a folder's two-stream HMC5883L recordings by their stem)
RECORDINGS = ("xio_fusion_sensor_data.csv", "hmc5883l_full-sphere", "hmc5883l_roll-and-tilt-at-45-90",
              "hmc5883l_rotate-ccw-around-x", "hmc5883l_rotate-ccw-around-y", "hmc5883l_rotate-ccw-around-z",
              "hmc5883l_unmoved-10min", "px4_sample.ulg", "px4_sample_log_small.ulg", "ardupilot_test.bin")


def command_cpu(path: Path, model: str, out: Path) -> tuple[float, str]:
    """``(CPU seconds, outcome)`` of one ``magexp calibrate`` command on ``path`` with ``model``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-m", "magexp", "calibrate", f"data.path={path}", f"model={model}",
                           f"out={out}"], capture_output=True, text=True, env=env, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    outcome = "accepted" if done.returncode == 0 else " ".join(done.stderr.strip().split())[:90]
    return cpu, outcome


def choice(path: Path) -> str:
    """What ``model=auto`` chooses on ``path`` and why (every candidate's held-out spread), or why nothing is chosen."""
    import magexp

    try:
        return magexp.calibrate(path, accept=True).report["model_selection"]["why"]
    except MagexpError as err:
        return f"no choice: {' '.join(str(err).split())[:120]}"


def measure(names, repeats: int) -> list[dict]:
    """One row per recording of ``names`` present: the median CPU of ``auto`` and ``full`` (interleaved
    ``repeats`` times), their ratio, the outcomes and ``auto``'s choice.
    """
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            path = SHARED_DATA / name
            if not (path.exists() or Path(f"{path}_mag.csv").exists()):
                continue
            cpu, outcome = {"auto": [], "full": []}, {}
            for k in range(repeats):
                for model in ("full", "auto"):
                    seconds, outcome[model] = command_cpu(path, model, Path(tmp) / f"{name}_{model}_{k}")
                    cpu[model].append(seconds)
            auto, full = statistics.median(cpu["auto"]), statistics.median(cpu["full"])
            rows.append({"recording": name, "auto_cpu_s": auto, "full_cpu_s": full, "ratio": auto / full,
                         "auto_outcome": outcome["auto"], "full_outcome": outcome["full"], "choice": choice(path)})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Print the cost of ``model=auto`` beside ``model=full`` on the shared recordings with a gyroscope."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs of each command (default 3)")
    parser.add_argument("--only", nargs="*", default=None, help="recordings of RECORDINGS to measure")
    args = parser.parse_args(argv)
    rows = measure(args.only or RECORDINGS, max(1, args.repeats))
    if not rows:
        print(f"no shared recording with a gyroscope in {SHARED_DATA}: nothing to measure")
        return 0
    print("| recording | auto CPU-s | full CPU-s | auto / full | auto | full |\n|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['recording']} | {r['auto_cpu_s']:.2f} | {r['full_cpu_s']:.2f} | {r['ratio']:.2f} | "
              f"{r['auto_outcome']} | {r['full_outcome']} |")
    print()
    for r in rows:
        print(f"{r['recording']}: auto chooses {r['choice']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
