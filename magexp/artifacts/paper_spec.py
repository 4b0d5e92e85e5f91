"""A paper's folder of ``experiments/``: its ``paper.yaml`` (title, deviations, headline claims and the
readings they are judged under) and its artifact files.

A headline claim is judged under its **primary reading**: the reading of what the paper left unstated that
its own words make most plausible, argued with a quote (``why``). The other readings are sensitivity
analyses: each names a source that states its settings and why it is less plausible than the primary
(``less_plausible``); they are run and shown, and summarised as the headline's robustness, but never decide
its verdict (:mod:`magexp.artifacts.headlines`)::

    headline:
      - id: ipso_more_accurate
        text: "Compared with the traditional PSO, the improved algorithm has higher solution accuracy ..."
        section: "Abstract; Sec. 3.1"
        parts: [ding2024_table_rms.paper_ipso_more_accurate_a2]     # the primary reading's claims
        primary: "constriction w = 0.7298, c = 1.49618"
        why: "Sec. 2.1 gives the traditional PSO as eq 10 with a fixed inertia w and fixed c1, c2 ..."
        readings:
          - label: "constriction w = 0.7298, c = 1.49618"
            source: "Clerc & Kennedy 2002"
            settings: "w = 0.7298, c1 = c2 = 1.49618, fixed"
          - label: "Shi & Eberhart 1998, w = 0.9, c = 2"
            source: "Shi & Eberhart 1998"
            settings: "w = 0.9, c1 = c2 = 2, fixed"
            less_plausible: "its inertia is at the top of the range Shi & Eberhart found slow to converge"
            parts: [ding2024_ext_pso_readings.paper_more_accurate_se09_a2]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from magexp.artifacts.schema import Int, build, typed
from magexp.artifacts.spec import check_unique_ids, read_yaml
from magexp.errors import MagexpError
from magexp.paths import EXPERIMENTS

#: longest label of a :class:`Reading` (the robustness sentence names readings by it)
READING_LABEL = 40
#: the verdict of a headline none of whose parts holds and none goes against (:func:`magexp.artifacts.headlines.headline_verdict`)
NOT_SHOWN = "not shown"
#: verdicts of a headline claim (its primary reading's: :mod:`magexp.artifacts.headlines`)
HEADLINE_VERDICTS = ("supported", "partly", "contradicted", NOT_SHOWN, "not testable here", "by construction")


@typed
@dataclass(frozen=True)
class Deviation:
    """Where magexp departs from (or has to read) the paper's text, and why."""

    text: str
    reason: str


@typed
@dataclass(frozen=True)
class Reading:
    """One sourced reading of a setting the paper leaves unstated (``readings:`` of a headline).

    ``label``: a short name (at most :data:`READING_LABEL` characters); ``source``: who states these
    settings (author and year, the paper's own words, or ``magexp's construction``); ``settings``: the
    settings that source states, as this reading runs them; ``parts``: the artifact claims
    (``<artifact>.<claim id>``) that test the headline under this reading (none: the headline's own
    ``parts``); ``less_plausible``: why the paper more plausibly meant its primary reading (required of
    every reading but the primary)."""

    label: str
    source: str
    settings: str = ""
    parts: list[str] = field(default_factory=list)
    less_plausible: str = ""

    def __post_init__(self):
        if len(str(self.label)) > READING_LABEL:
            raise MagexpError(f"reading {self.label!r}: the label is {len(str(self.label))} characters: at most "
                              f"{READING_LABEL} are allowed (the source says the rest)")
        _check_parts(self.parts, f"reading {self.label!r}")


def _check_parts(parts: list, where: str) -> None:
    """Raise unless every part is written ``<artifact>.<claim id>``."""
    for part in parts:
        if not isinstance(part, str) or part.count(".") != 1:
            raise MagexpError(f"{where}: part {part!r} is not allowed: write <artifact>.<claim id>")


@typed
@dataclass(frozen=True)
class Headline:
    """A headline claim of the paper (``headline:`` of ``paper.yaml``), in the paper's own words.

    ``parts``: the artifact claims (``<artifact>.<claim id>``) that test it; its verdict is ``supported``
    (every part holds), ``partly`` (some hold), ``contradicted`` (none holds, one goes against it), ``not shown``
    (none holds, none goes against it), or ``not testable here`` when
    ``untestable`` (why) is given instead of parts. A claim about *every* instance ("any two axes", "all
    noise levels") lists each instance as a part: one that fails makes it ``partly`` at best. ``reason``: an
    optional template interpolated with the runs of the first part's artifact
    (:func:`magexp.artifacts.claims.interpolate`). ``figure``: ``<paper folder>/<artifact>`` whose figure
    shows it. ``construction``: why its parts hold by construction (then a ``supported`` verdict reads ``by
    construction`` and is not counted as support). ``readings``: the sourced readings of what it leaves
    unstated (:class:`Reading`); ``primary`` names the one that decides the verdict and ``why`` argues it
    from the paper's text (section and words); the others test its robustness."""

    id: str
    text: str
    section: str
    figure: str = ""
    parts: list[str] = field(default_factory=list)
    reason: str = ""
    untestable: str = ""
    construction: str = ""
    primary: str = ""
    why: str = ""
    readings: list[Reading] = field(default_factory=list)

    def __post_init__(self):
        if bool(self.parts) == bool(str(self.untestable).strip()):
            raise MagexpError(f"headline {self.id!r}: give either parts (artifact.claim ids) or untestable (why), not both or neither")
        _check_parts(self.parts, f"headline {self.id!r}")
        if self.figure and str(self.figure).count("/") != 1:
            raise MagexpError(f"headline {self.id!r}: figure={self.figure!r} is not allowed: write <paper folder>/<artifact>")
        if not self.readings:
            if str(self.primary).strip():
                raise MagexpError(f"headline {self.id!r}: primary={self.primary!r} names no reading: declare readings")
            return
        self._check_readings()

    def _check_readings(self) -> None:
        """Raise unless the readings are a choice with one primary reading, argued, and every other
        reading says why it is less plausible."""
        labels = [str(r.label) for r in self.readings]
        if len(labels) == 1:
            raise MagexpError(f"headline {self.id!r}: one reading is no choice: declare at least two, or none")
        if len(set(labels)) != len(labels):
            raise MagexpError(f"headline {self.id!r}: two readings share a label: each needs its own")
        if self.primary not in labels:
            raise MagexpError(f"headline {self.id!r}: primary={self.primary!r} is not allowed: name one of its "
                              "readings (" + ", ".join(repr(x) for x in labels) + ")")
        if not str(self.why).strip():
            raise MagexpError(f"headline {self.id!r}: why is missing: quote the paper's words that make "
                              f"{self.primary!r} its most plausible reading")
        if sum(not r.parts for r in self.readings) > 1:
            raise MagexpError(f"headline {self.id!r}: only one reading may leave out parts (the headline's own)")
        for r in self.readings:
            if r.label != self.primary and not str(r.less_plausible).strip():
                raise MagexpError(f"headline {self.id!r}: reading {r.label!r} needs less_plausible: why the paper "
                                  f"more plausibly meant {self.primary!r}")
            if not r.parts and r.label != self.primary:
                raise MagexpError(f"headline {self.id!r}: reading {r.label!r} leaves out parts, which are the "
                                  "headline's own: only the primary reading may")

    def primary_parts(self) -> list[str]:
        """The claims that decide the verdict: the primary reading's parts, else the headline's own."""
        for r in self.readings:
            if r.label == self.primary and r.parts:
                return list(r.parts)
        return list(self.parts)

    def sensitivity_parts(self) -> list[str]:
        """The claims that re-test the headline under its other readings (sensitivity analyses)."""
        primary = set(self.primary_parts())
        return [p for r in self.readings if r.label != self.primary for p in r.parts if p not in primary]


@typed
@dataclass(frozen=True)
class Paper:
    """``experiments/<paper>/paper.yaml``: the report section's title, intro, order, headline claims
    (:class:`Headline`) and deviations."""

    title: str
    intro: str = ""
    order: Int = 100
    deviations: list[Deviation] = field(default_factory=list)
    requires_data: list[str] = field(default_factory=list)  # recordings its artifacts read (skipped when absent)
    headline: list[Headline] = field(default_factory=list)


def load_paper(paper: str, root: Path | None = None) -> Paper:
    """The validated ``paper.yaml`` of ``paper``."""
    path = (root or EXPERIMENTS) / paper / "paper.yaml"
    data = (read_yaml(path) or {}) if path.exists() else {"title": paper}
    meta = build(Paper, data, f"{paper}/paper.yaml")
    check_unique_ids(meta.headline, f"{paper}/paper.yaml.headline")
    return meta


def check_headlines(paper: str, headlines: list, specs: list) -> None:
    """Raise :class:`~magexp.errors.MagexpError` unless every part of each headline (and of its readings)
    names a claim ``<artifact>.<claim id>`` of ``specs``: checked when a paper's artifacts are read, before
    any run.

    Parameters
    ----------
    paper : str
        The paper (its folder).
    headlines : list of Headline
        Its ``paper.yaml`` headlines.
    specs : list of Artifact
        Its artifacts.
    """
    declared = {f"{s.name}.{c.id}" for s in specs for c in s.claims}
    for h in headlines:
        for part in [p for p in list(h.parts) + [p for r in h.readings for p in r.parts] if p not in declared]:
            artifact = part.split(".")[0]
            ids = [c.id for s in specs if s.name == artifact for c in s.claims]
            exists = (f"{artifact} has claims {', '.join(ids)}" if ids else
                      f"artifacts with claims: {', '.join(s.name for s in specs if s.claims)}")
            raise MagexpError(f"{paper}/paper.yaml headline {h.id!r}: part {part!r} names no claim of {paper} "
                              f"(write <artifact>.<claim id>; {exists})")


def papers(root: Path | None = None) -> list[str]:
    """Every folder of ``experiments/`` that holds an artifact YAML, in the papers' ``order``
    (``paper.yaml``, optional: title, intro, order, deviations).
    """
    root = root or EXPERIMENTS
    names = [p.name for p in root.iterdir() if p.is_dir() and any(q.name != "paper.yaml" for q in p.glob("*.yaml"))]
    return sorted(names, key=lambda n: (load_paper(n, root).order, n))


def artifact_paths(paper: str, root: Path | None = None) -> list[Path]:
    """The artifact files of ``paper``, in file-name order."""
    root = root or EXPERIMENTS
    folder = root / paper
    if not folder.is_dir() or paper not in papers(root):
        raise MagexpError(f"paper={paper!r} is not allowed: choose one of {', '.join(papers(root))}")
    return sorted(p for p in folder.glob("*.yaml") if p.name != "paper.yaml")
