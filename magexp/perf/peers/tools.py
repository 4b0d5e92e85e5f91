"""magexp beside the calibration tools pilots use (issue 33 item 8): ``magcal`` 1.0.1 and ``circuitpython-mag-cal``
1.4.1 on every shared recording, measured the same way as magexp.

``python -m magexp.perf.peers.tools --out results/peers`` (``make peers-tools-bench``) writes ``DIR/tools.csv``
(one row per recording and side) and ``DIR/tools.md`` (the table). The tools run in their own environment
(``make peers-tools``: ``.peers/tools-venv`` from ``requirements-peers-tools.lock``; ``MAGEXP_PEER_TOOLS`` names
another), through :mod:`.tools_side` in a subprocess: magexp never imports them, nor they magexp. Without that
environment it prints one line and writes nothing.

Every side is judged by the same measures, on the readings magexp reads (a log's onboard calibration undone):

* ``spread_raw``, ``spread_after``: std / mean of ``|r|`` and ``|B|`` over every reading;
* ``heldout_spread``: the readings cut into magexp's six regions of directions
  (:func:`magexp.calibration.fit.regions`), each region of at least 12 readings calibrated by the side's fit on
  the others, the held-out magnitudes pooled (:func:`magexp.calibration.fit.heldout`): NaN where a fold fails;
* ``seconds``: process time of one fit on every reading (the tools' own calls only; magexp's row: the whole
  default ``magexp.calibrate``, model selection, held-out folds and gate included);
* ``outcome``: magexp ``accepted`` or ``refused`` with the first failed check; a tool ``refused`` (its own
  exception), ``NaN`` (a non-finite calibration returned without a word), ``worse than raw`` (a spread, in
  sample or held out, above the raw one, returned without a word: neither tool has a gate) or ``returned``.
  ``magexp (accept=true)`` is magexp's calibration written anyway, to set its numbers beside the tools' where
  magexp refuses.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import magexp
from magexp.calibration.checks import MIN_READINGS
from magexp.calibration.fit import regions
from magexp.core.identifiability import spread
from magexp.core.recordings import load_recording
from magexp.errors import MagexpError
from magexp.paths import ROOT, SHARED_DATA

#: the tools' interpreter (``make peers-tools``)
TOOLS_VENV = Path(os.environ.get("MAGEXP_PEER_TOOLS", ROOT / ".peers" / "tools-venv"))
TOOLS_SCRIPT = Path(__file__).with_name("tools_side.py")
TOOLS = ("magcal", "circuitpython-mag-cal")
#: the unit of a shared recording whose file does not name it (the data README: the FXOS8700's readings in µT)
UNITS = {"fxos8700_mag_readings.txt": "uT"}
COLUMNS = ("recording", "n", "side", "version", "outcome", "spread_raw", "spread_after", "heldout_spread", "seconds")


def recordings(folder: Path = SHARED_DATA) -> list[Path]:
    """Every recording of the shared data folder: a two-stream recording by its stem, the others by file."""
    out = []
    for path in sorted(Path(folder).iterdir()):
        if path.name.endswith("_imu.csv") or path.suffix.lower() == ".md":
            continue
        out.append(path.with_name(path.name[: -len("_mag.csv")]) if path.name.endswith("_mag.csv") else path)
    return out


def available() -> str | None:
    """None when the tools' environment is there, else the one line saying why not."""
    if not (TOOLS_VENV / ".installed").exists():
        return f"the tools' environment {TOOLS_VENV} is absent (make peers-tools builds it): nothing written"
    return None


def magexp_row(path: Path, *, accept: bool = False) -> dict:
    """magexp's default calibration of ``path`` (``accept``: written whatever the gate says)."""
    start = time.process_time()
    try:
        cal = magexp.calibrate(path, unit=UNITS.get(path.name), accept=accept)
    except MagexpError as exc:
        reason = str(exc).split(": ", 1)[-1]
        return {"side": "magexp" + (" (accept=true)" if accept else ""), "version": magexp.__version__,
                "outcome": "refused: " + reason[:160], "seconds": time.process_time() - start}
    m, gate = cal.metrics, cal.report.get("gate") or {}
    outcome = (f"accepted ({cal.model})" if gate.get("passed")
               else "written, gate failed: " + ", ".join(f["check"] for f in gate.get("failed", [])))
    return {"side": "magexp" + (" (accept=true)" if accept else ""), "version": magexp.__version__,
            "outcome": outcome, "spread_after": m["spread_after"], "heldout_spread": m.get("heldout_spread"),
            "seconds": time.process_time() - start}


def run_tools(readings: np.ndarray, work: Path) -> tuple[dict, list[int], np.ndarray]:
    """The tools' answer (:mod:`.tools_side`) on ``readings``, the folds held out and each reading's region."""
    labels, _ = regions(readings)
    folds = [k for k in range(6) if np.count_nonzero(labels == k) >= MIN_READINGS]
    folds = folds if len(folds) >= 2 else []  # fewer than two: nothing held out (as magexp's heldout)
    source, out = work / "in.npz", work / "out.json"
    np.savez(source, mag=readings, labels=labels, folds=np.array(folds, int))
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    env.update({"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"})
    proc = subprocess.run([str(TOOLS_VENV / "bin" / "python"), str(TOOLS_SCRIPT), str(source), str(out)],
                          capture_output=True, text=True, timeout=600, env=env)
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise MagexpError(f"the tools' side failed (exit {proc.returncode}): {tail}")
    return json.loads(out.read_text()), folds, labels


def tool_row(name: str, fits: dict, readings: np.ndarray, folds: list[int], labels: np.ndarray) -> dict:
    """One tool's row (module docstring) from its fits on every reading and on each fold."""
    whole = fits["all"]
    row = {"side": name, "seconds": whole["seconds"]}
    if whole["error"]:
        return {**row, "outcome": "refused: " + whole["error"]}
    apply = lambda fit, r: (r - np.asarray(fit["o"])) @ np.asarray(fit["W"]).T  # noqa: E731
    after = np.linalg.norm(apply(whole, readings), axis=1)
    row["spread_after"] = spread(after) if np.all(np.isfinite(after)) else float("nan")
    row["heldout_spread"], why = _tool_heldout(fits, readings, folds, labels)
    if not np.isfinite(row["spread_after"]):
        row["outcome"] = "NaN returned without a word"
    elif max(row["spread_after"], np.nan_to_num(row["heldout_spread"])) >= spread(np.linalg.norm(readings, axis=1)):
        row["outcome"] = "returned, worse than raw (no gate)" + (f"; held out: {why}" if why else "")
    else:
        row["outcome"] = "returned (no gate)" + (f"; held out: {why}" if why else "")
    return row


def _tool_heldout(fits: dict, readings: np.ndarray, folds: list[int], labels: np.ndarray) -> tuple[float, str]:
    """``(held-out spread, why it is NaN)`` of a tool's fold fits (the pooling of
    :func:`magexp.calibration.fit.heldout`)."""
    if len(folds) < 2:
        return float("nan"), "the readings reach fewer than two regions of directions"
    refused = [fits[str(k)]["error"] for k in folds if fits[str(k)]["error"]]
    if refused:
        return float("nan"), f"a fold refused ({refused[0]})"
    held = np.concatenate([np.linalg.norm((readings[labels == k] - np.asarray(fits[str(k)]["o"]))
                                          @ np.asarray(fits[str(k)]["W"]).T, axis=1) for k in folds])
    if not np.all(np.isfinite(held)):
        return float("nan"), "a fold returned NaN"
    return spread(held), ""


def rows_of(path: Path) -> list[dict]:
    """Every side's row on one recording."""
    try:
        readings = load_recording(path, unit=UNITS.get(path.name)).readings
    except MagexpError as exc:
        return [{"recording": path.name, "side": "magexp", "outcome": f"unreadable: {exc}"}]
    base = {"recording": path.name, "n": len(readings), "spread_raw": spread(np.linalg.norm(readings, axis=1))}
    rows = [magexp_row(path), magexp_row(path, accept=True)]
    with tempfile.TemporaryDirectory() as tmp:
        answer, folds, labels = run_tools(readings, Path(tmp))
    for name in TOOLS:
        rows.append({**tool_row(name, answer["fits"][name], readings, folds, labels),
                     "version": answer["versions"][name]})
    return [{**base, **row} for row in rows]


def percent(value) -> str:
    """``value`` in percent (3 significant digits); empty for none."""
    return "" if value is None or value == "" else ("NaN" if not np.isfinite(value) else f"{100 * value:.3g}")


def table(rows: list[dict]) -> str:
    """The markdown table of ``rows``."""
    lines = ["| recording | n | side | outcome | raw % | after % | held out % | CPU s |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['recording']} | {r.get('n', '')} | {r['side']} | {r['outcome'].replace('|', '/')} | "
                     f"{percent(r.get('spread_raw'))} | {percent(r.get('spread_after'))} | "
                     f"{percent(r.get('heldout_spread'))} | {r.get('seconds', float('nan')):.3g} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Compare the tools on every shared recording; ``tools.csv`` and ``tools.md`` in ``--out``."""
    p = argparse.ArgumentParser(prog="python -m magexp.perf.peers.tools", description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True, type=Path, help="folder of tools.csv and tools.md")
    args = p.parse_args(argv)
    why = available()
    if why:
        print(why, file=sys.stderr)
        return 2
    rows = [row for path in recordings() for row in rows_of(path)]
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "tools.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    text = ("# magexp beside magcal and circuitpython-mag-cal\n\n"
            "Generated by `make peers-tools-bench` (`python -m magexp.perf.peers.tools --out results/peers`); "
            "the measures: `magexp/perf/peers/tools.py`.\n\n" + table(rows) + "\n")
    (args.out / "tools.md").write_text(text)
    print(f"wrote {args.out / 'tools.csv'} and {args.out / 'tools.md'} ({len(rows)} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
