"""Assemble ``results/summary.csv``, ``results/versions.csv`` and ``results/REPORT.md`` from the
papers' parts: per paper its verdicts, its claims (each with its evidence and whether it holds),
its deviations from the paper's text, and every artifact with its table and notes (measured
values interpolated from the runs, :func:`magexp.claims.interpolate`)."""

from __future__ import annotations

import functools
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.claims import evaluate, interpolate
from magexp.paths import RESULTS
from magexp.spec import ROUNDOFF_FLOOR, artifact_paths, load, load_paper, papers
from magexp.summary import COLUMNS, VERDICTS

#: significant digits of every float written to a results CSV (round-off must not churn files)
DIGITS = 6
SUMMARY_SHOWN = ["quantity", "estimator", "setting", "truth", "paper_value", "value", "lo", "hi", "success_rate",
                 "n_seeds", "truth_in_interval", "verdict"]


def _floats(column: pd.Series) -> np.ndarray | None:
    """The column as floats if it holds floats: a float column, or an object column whose values are
    floats and missing values (e.g. a truth that some rows lack); else None (text, integers, flags)."""
    if pd.api.types.is_float_dtype(column):
        return column.to_numpy(float)
    if column.dtype == object:
        present = [v for v in column if v is not None and not (isinstance(v, float) and np.isnan(v))]
        if present and all(isinstance(v, (float, np.floating)) for v in present):
            return np.array([np.nan if v is None else float(v) for v in column])
    return None


def tidy(frame: pd.DataFrame, floor: float = ROUNDOFF_FLOOR) -> pd.DataFrame:
    """Float columns with magnitudes below ``floor`` (round-off, e.g. a noise-free RMS of 1e-11)
    written as ``±floor``; every float then rounded to :data:`DIGITS` significant digits."""
    out = frame.copy()
    for col in out.columns:
        v = _floats(out[col])
        if v is not None:
            small = np.isfinite(v) & (v != 0) & (np.abs(v) < floor)
            v = np.where(small, np.sign(v) * floor, v)
            with np.errstate(divide="ignore", invalid="ignore"):
                mag = np.where(np.isfinite(v) & (v != 0), np.floor(np.log10(np.abs(np.where(v == 0, 1, v)))), 0)
            scale = 10.0 ** (DIGITS - 1 - mag)
            out[col] = np.where(np.isfinite(v), np.round(v * scale) / scale, v)
    return out


def write_csv(frame: pd.DataFrame, path: Path) -> None:
    """A results CSV: :func:`tidy` values, ``%.6g`` floats (identical bytes on every fresh clone
    when only round-off differs)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")  # atomic: an interrupt leaves the old file or the new one
    tidy(frame).to_csv(tmp, index=False, float_format=f"%.{DIGITS}g")
    os.replace(tmp, path)


def versions() -> dict:
    """The versions behind the results: python and the libraries (:mod:`magexp.provenance`) and
    ``magexp_commit``, the last commit that changed anything outside ``results/`` (so committing the
    regenerated results does not change the record, and a fresh clone writes the same bytes)."""
    from magexp import provenance

    try:
        commit = subprocess.run(["git", "log", "-1", "--format=%h", "--abbrev=12", "--", ".", ":(exclude)results"],
                                capture_output=True, text=True, check=True,
                                cwd=Path(__file__).resolve().parent.parent).stdout.strip() or provenance.commit()
    except (OSError, subprocess.CalledProcessError):
        commit = provenance.commit()
    libs = provenance.provenance()
    return {**{k: v for k, v in libs.items() if k not in ("magexp_commit", "config_hash", "commit")},
            "magexp_commit": commit}


def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return f"{v:.4g}"
    return str(v)


_LATEX = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{",
          "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}


def _tex(text: str) -> str:
    return "".join(_LATEX.get(ch, ch) for ch in str(text))


def latex_table(frame: pd.DataFrame, columns: list[str]) -> str:
    """The same table as :func:`markdown_table`, as a LaTeX ``tabular`` with ``booktabs`` rules
    (``\\usepackage{booktabs}``), ready to ``\\input`` into a paper."""
    lines = [r"\begin{tabular}{" + "l" * len(columns) + "}", r"\toprule",
             " & ".join(_tex(c) for c in columns) + r" \\", r"\midrule"]
    lines += [" & ".join(_tex(_fmt(r[c])) for c in columns) + r" \\" for _, r in frame.iterrows()]
    return "\n".join(lines + [r"\bottomrule", r"\end{tabular}", ""])


def markdown_table(frame: pd.DataFrame, columns: list[str], tex: Path | None = None) -> str:
    """A Markdown table of ``columns``; with ``tex``, its LaTeX twin (:func:`latex_table`) is written there."""
    if tex is not None:
        Path(tex).write_text(latex_table(frame, columns))
    head = "| " + " | ".join(columns) + " |\n|" + "---|" * len(columns) + "\n"
    return head + "".join("| " + " | ".join(_fmt(r[c]) for c in columns) + " |\n" for _, r in frame.iterrows())


def collect(root: Path = RESULTS) -> pd.DataFrame:
    """Every paper's summary part, in the papers' order."""
    parts = []
    for paper in papers():
        path = root / paper / "summary.csv"
        if path.exists() and path.stat().st_size > 0:
            part = pd.read_csv(path, keep_default_na=False, na_values=[""])
            parts.append(part.reindex(columns=COLUMNS))
    if not parts:
        return pd.DataFrame(columns=COLUMNS)
    return pd.concat(parts, ignore_index=True)[COLUMNS]


def _runs(root: Path, paper: str, name: str) -> pd.DataFrame | None:
    path = root / paper / f"{name}_runs.csv"
    return pd.read_csv(path) if path.exists() else None


def _runs_reader(root: Path, paper: str):
    """``name -> runs table`` of ``paper``: each runs CSV read once, however many sections use it."""
    return functools.cache(lambda name: _runs(root, paper, name))


def _outcomes(specs: list, runs) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim of ``specs`` whose runs table (``runs(name)``) has rows."""
    out = []
    for spec in specs:
        table = runs(spec.name) if spec.claims else None
        if table is not None and len(table):
            out += [(spec.name, evaluate(c, table)) for c in spec.claims]
    return out


def claim_outcomes(root: Path = RESULTS, paper: str | None = None) -> list[tuple[str, object]]:
    """``(artifact, Outcome)`` of every claim whose artifact has runs under ``root``."""
    return [o for p in ([paper] if paper else papers())
            for o in _outcomes([load(path) for path in artifact_paths(p)], _runs_reader(root, p))]


def _claims_section(root: Path, paper: str, specs: list, runs) -> str:
    outcomes = _outcomes(specs, runs)
    if not outcomes:
        return ""
    frame = pd.DataFrame([{"artifact": name, "by": o.claim.by, "claim": o.claim.text, "evidence": o.evidence,
                           "result": "holds" if o.holds else "does not hold"} for name, o in outcomes])
    table = markdown_table(frame, list(frame.columns), tex=root / paper / "claims.tex")
    return ("### Claims\n\nEach qualitative statement, as a condition on the runs (`claims:` in the artifact "
            "YAML). *magexp*: stated by this report (a test fails if one does not hold); *paper*: the paper's "
            "statement, checked. Intervals: 95 % bootstrap over seeds.\n\n"
            + table.replace("| does not hold |", "| **does not hold** |"))


def _deviations_section(meta, paper: str, root: Path) -> str:
    if not meta.deviations:
        return ""
    frame = pd.DataFrame([{"what": d.text.strip(), "why": d.reason.strip()} for d in meta.deviations])
    return "### Deviations from the paper's text\n\n" + markdown_table(frame, ["what", "why"],
                                                                        tex=root / paper / "deviations.tex")


def _paper_section(paper: str, summary: pd.DataFrame, root: Path) -> str:
    """A paper's section; each spec parsed and each runs CSV read once for all its parts."""
    meta = load_paper(paper)
    specs = [load(path) for path in artifact_paths(paper)]
    runs = _runs_reader(root, paper)
    lines = [f"## {meta.title}\n", f"{meta.intro}\n"]
    rows = summary[summary.paper == paper]
    counts = rows.verdict.value_counts()
    if len(rows):
        lines.append(f"Verdicts: {', '.join(f'{k} {int(counts.get(k, 0))}' for k in VERDICTS)}.\n")
    lines.append(_claims_section(root, paper, specs, runs))
    lines.append(_deviations_section(meta, paper, root))
    for spec in specs:
        if not (root / paper / f"{spec.name}.png").exists():
            continue
        table = runs(spec.name)
        lines.append(f"### {spec.name}: {spec.title}\n")
        lines.append(f"![{spec.name}]({paper}/{spec.name}.png)\n")
        if spec.caption:
            lines.append(f"{_prose(spec, spec.caption, table)}\n")
        timing = (f", wall times on this machine: [`timing/{spec.name}.csv`](timing/{spec.name}.csv)"
                  if (root / "timing" / f"{spec.name}.csv").exists() else "")
        lines.append(f"Data: [`{paper}/{spec.name}.csv`]({paper}/{spec.name}.csv), "
                     f"runs: [`{paper}/{spec.name}_runs.csv`]({paper}/{spec.name}_runs.csv){timing}.\n")
        art = rows[rows.artifact == spec.name]
        if len(art):
            lines.append(markdown_table(art, SUMMARY_SHOWN, tex=root / paper / f"{spec.name}_summary.tex"))
        if spec.report_table:
            lines.append(_artifact_table(spec, root / paper / f"{spec.name}.csv"))
        if spec.notes:
            lines.append(f"\n{_prose(spec, spec.notes, table)}\n")
    return "\n".join(lines)


def _prose(spec, text: str, table: pd.DataFrame | None) -> str:
    """A caption or note with its measured values filled in: ``{seeds}`` (the seeds of its runs)
    and every ``{stat:metric@selection:format}`` field (:func:`magexp.claims.interpolate`)."""
    seeds = table.seed.nunique() if table is not None and "seed" in table else spec.seeds
    text = str(text).strip().replace("{seeds}", str(seeds))
    return interpolate(text, table) if table is not None else text


def _artifact_table(spec, path: Path) -> str:
    """The artifact's own CSV as a table (columns ``report_table``), and the winner per case."""
    from magexp.plots.benchmark_table import winners

    frame = pd.read_csv(path)
    cols = [c for c in spec.report_table if c in frame]
    text = markdown_table(frame, cols, tex=path.with_name(f"{spec.name}_table.tex"))
    by = "bound_ratio" if "bound_ratio_hi" in frame and frame.bound_ratio_hi.notna().any() else spec.plot.get("metric")
    if "case" in frame and by and f"{by}_hi" in frame:  # recordings: no bound, the held-out spread
        simulated = by == "bound_ratio"
        what = "RMS offset error / sqrt(tr CRB)" if simulated else str(by).replace("_", " ")
        among = "" if simulated else "; among the estimators that succeed on at least half the runs"
        ranked = frame if simulated else frame[frame.success_rate >= 0.5]
        text += (f"\n**Winner per case** (lowest {what}; declared only where its 95 % interval lies below every "
                 f"other estimator's; else no winner, and the estimators whose intervals overlap the best{among}):\n\n"
                 + markdown_table(winners(ranked, by), ["case", "winner", by, f"{by}_lo", f"{by}_hi", "success_rate",
                                                        "tied"], tex=path.with_name(f"{spec.name}_winners.tex")))
    return text


def _speed_section(root: Path) -> str:
    path = root / "bench.csv"
    if not path.exists():
        return ""
    frame = pd.read_csv(path)
    cols = [c for c in ("measure", "estimator", "value", "unit", "lo", "hi") if c in frame]
    return ("## Speed of the core (`make bench`)\n\nMeasured by `make bench` on this machine, side by side in one "
            "run (variants alternating, one BLAS thread): medians with the interquartile range (`lo`-`hi`), or a "
            "95 % interval for success rates ([`bench.csv`](bench.csv); the sections are described in the README)."
            "\n\n" + markdown_table(frame, cols, tex=root / "bench.tex"))


def build(root: Path = RESULTS) -> None:
    """Write ``root/summary.csv``, ``root/versions.csv`` and ``root/REPORT.md``."""
    summary = collect(root)
    write_csv(summary, root / "summary.csv")
    record = versions()
    pd.DataFrame([{"package": k, "version": v} for k, v in record.items()]).to_csv(root / "versions.csv", index=False)
    counts = summary.verdict.value_counts()
    text = [
        "# magexp report\n",
        "Every number below is regenerated by `make reproduce` (one paper: `make reproduce-<paper>`). "
        "A paper reports one run; `value` is our median over seeds and `lo`-`hi` the interval a single run of "
        "ours falls in (2.5-97.5 % over seeds). Verdict `reproduced`: the paper's value is in that interval "
        "(widened only by the paper's printing precision) and at least half the runs succeeded; `differs`: "
        "not; `n/a`: the paper gives no number. `success_rate`: the fraction of runs within the stated "
        "factor of the optimum the true calibration gives (`success:` of the artifact). "
        "`truth_in_interval`: the true calibration's value is in the interval too (then the row shows "
        "convergence to the noise floor, not more). All rows: [`summary.csv`](summary.csv); versions: "
        "[`versions.csv`](versions.csv) (" + ", ".join(f"{k} {v}" for k, v in record.items()) + ").\n",
        f"Overall: {len(summary)} summary rows; "
        + ", ".join(f"{k} {int(counts.get(k, 0))}" for k in VERDICTS) + ".\n",
    ]
    text += [_paper_section(p, summary, root) for p in papers() if (summary.paper == p).any() or (root / p).is_dir()]
    text.append(_speed_section(root))
    (root / "REPORT.md").write_text("\n".join(text))


if __name__ == "__main__":
    build(Path(sys.argv[1]) if len(sys.argv) > 1 else RESULTS)
