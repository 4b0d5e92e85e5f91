"""The key of a run: a digest of everything the run reads.

The key of a run (:func:`run_key`) hashes

* its fully resolved config (every setting, the seed included),
* the content of every data file the config names (:func:`magexp.core.datafiles.data_files`), so that editing a
  recording such as ``data/yan2022_mockup.csv`` reruns exactly the runs that read it,
* the source of the code the run executes (:func:`code_version`): the modules of what it names
  (:func:`run_targets`: every ``_target_`` of its config, the reader of each data file it reads, its
  objective's problem class) with their import closure and the core every run executes, found and hashed by
  :mod:`magexp.run.codekey` and kept under the sources' stamp. So an estimator edit reruns the runs of that
  estimator and of the estimators importing its module, a reader edit the runs reading a file of its format,
  and code downstream of a run (``plots/``, ``summary``, ``report``, ``reproduce``, the executor, the run
  cache) is not part of any key: a figure or report edit costs no run.

The runs are stored under their keys by :mod:`magexp.run.cache`.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from magexp.core.datafiles import data_files, data_formats
from magexp.core.readers import reader_of
from magexp.problems import OBJECTIVES
from magexp.run import cache
from magexp.run.codekey import code_hash, default_objective, source_stamp


def files_digest(files, base: Path):
    """A SHA-256 object fed with the path (relative to ``base``) and content of each of ``files``."""
    h = hashlib.sha256()
    for path in files:
        h.update(path.relative_to(base).as_posix().encode())
        h.update(path.read_bytes())
    return h


def _targets_in(node, found: set) -> set:
    """Every ``_target_`` string in a config tree (nested strategy objects included), added to ``found``."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key == "_target_" and isinstance(value, str):
                found.add(value)
            else:
                _targets_in(value, found)
    elif isinstance(node, (list, tuple)):
        for value in node:
            _targets_in(value, found)
    return found


def data_readers(formats: dict) -> set[str]:
    """The readers of a config's data files (``formats``: its :func:`magexp.core.datafiles.data_formats`):
    the dotted name of the function reading each (:func:`magexp.core.readers.reader_of`) in the
    format named beside it, else in the one detected from its name or first lines. None is imported: a
    log's reader module is imported by name when the log is read."""
    return {reader_of(path, format) for path, format in formats.items()}


def run_targets(resolved: dict, formats: dict | None = None) -> tuple[str, ...]:
    """What a run instantiates or calls by name: every ``_target_`` of its resolved config, the reader of
    each data file it names (:func:`data_readers`; ``formats``: its data files' formats, found here if
    None), and the problem class of its objective (``objective``, else its scenario's: in its config,
    else fixed by its class, :func:`magexp.run.codekey.default_objective`; one not found so: every registered problem
    class)."""
    formats = data_formats(resolved) if formats is None else formats
    found = _targets_in(resolved, set()) | data_readers(formats)
    scenario = resolved.get("scenario") if isinstance(resolved.get("scenario"), dict) else {}
    objective = resolved.get("objective") or scenario.get("objective")
    if objective is None and isinstance(scenario.get("_target_"), str):
        objective = default_objective(scenario["_target_"])
    problems = [OBJECTIVES[objective]] if objective in OBJECTIVES else list(OBJECTIVES.values())
    found.update(p.replace(":", ".") for p in problems)
    return tuple(sorted(found))


def code_versions(target_sets) -> dict[tuple, str]:
    """:func:`code_version` of each tuple of ``target_sets``, the memo read and written once.

    Finding the code of a run parses the modules of its closure (about 20 ms for one run's, 60 ms
    for every run of ``reproduce all``). The versions of targets that are all magexp's are kept in
    the run cache folder (``code-version.json``, beside the results' two-letter folders) under the
    sources' :func:`magexp.run.codekey.source_stamp`, so a later command with unchanged sources reads
    them instead (a changed stamp only recomputes them: never a stale version). A target of another package is
    worked out each time: the stamp does not cover its files."""
    memo, stamp = cache.CACHE / "code-version.json", source_stamp()
    try:
        known = json.loads(memo.read_text())
        known = known if isinstance(known, dict) else {}
    except (OSError, ValueError):
        known = {}
    kept = known.get(stamp) if isinstance(known.get(stamp), dict) else {}
    versions, new = {}, {}
    for targets in dict.fromkeys(target_sets):
        name = "|".join(targets)
        if isinstance(kept.get(name), str):
            versions[targets] = kept[name]
            continue
        versions[targets] = code_hash(targets)
        if all(t.startswith("magexp.") for t in targets):
            new[name] = versions[targets]
    if new:
        known = {**{k: v for k, v in list(known.items())[-7:] if k != stamp}, stamp: {**kept, **new}}  # the last few trees
        try:
            cache.write(memo, json.dumps(known).encode(), cache.CACHE)
        except OSError:  # a read-only cache folder: worked out each time
            pass
    return versions


def code_version(targets: tuple[str, ...] = ()) -> str:
    """Hash of the code a run of ``targets`` (its :func:`run_targets`) executes: the name and content of
    each file of :func:`magexp.run.codekey.code_files`. Only an edit of such a file invalidates the run."""
    return code_versions([tuple(targets)])[tuple(targets)]


def run_key(resolved: dict, files: dict[str, str] | None = None, code: str | None = None) -> str:
    """Key of a run: its resolved config, the content of the data files it names, the code it executes."""
    files = data_files(resolved) if files is None else files
    code = code_version(run_targets(resolved)) if code is None else code
    return _key_of(json.dumps(resolved, sort_keys=True, default=str), files, code)


def _key_of(text: str, files: dict[str, str], code: str) -> str:
    """:func:`run_key` from the config's sorted JSON ``text``: one place that hashes a key."""
    if files:
        text += json.dumps(sorted(files.values()))
    return hashlib.sha256((text + code).encode()).hexdigest()[:32]


def _sorted_json(cfg: dict, parts: dict) -> str:
    """``json.dumps(cfg, sort_keys=True, default=str)`` of a config with string keys, each top-level value's
    text taken from ``parts`` (by identity: the seeds of a cell share every value but their seed)."""
    texts = []
    for name in sorted(cfg):
        value = cfg[name]
        if id(value) not in parts:
            parts[id(value)] = (value, json.dumps(value, sort_keys=True, default=str))
        texts.append(f"{json.dumps(name)}: {parts[id(value)][1]}")
    return "{" + ", ".join(texts) + "}"


def run_keys(configs) -> list[str]:
    """:func:`run_key` of each config; its data files and code version are looked up once per config
    that differs in more than its seed, and each top-level value written as JSON once (:func:`_sorted_json`)."""
    known: dict[str, tuple] = {}
    texts, rests, parts = [], [], {}  # parts hold their values: an id is not reused meanwhile
    for cfg in configs:
        plain = all(isinstance(name, str) for name in cfg)
        text = _sorted_json(cfg, parts) if plain else json.dumps(cfg, sort_keys=True, default=str)
        rest = _sorted_json({k: v for k, v in cfg.items() if k != "seed"}, parts) if plain else \
            json.dumps({k: v for k, v in cfg.items() if k != "seed"}, sort_keys=True, default=str)
        if rest not in known:
            formats = data_formats(cfg)
            known[rest] = (data_files(cfg, formats), run_targets(cfg, formats))
        texts.append(text)
        rests.append(rest)
    versions = code_versions(targets for _, targets in known.values())
    return [_key_of(text, known[rest][0], versions[known[rest][1]]) for text, rest in zip(texts, rests)]
