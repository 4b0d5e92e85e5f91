"""The one place that composes configurations: the CLI, reproduce, bench, calibrate and the tests.

A run config is Hydra's composition of ``conf/config.yaml`` with one choice per config group
(``conf/scenario/*.yaml``, ``conf/estimator/*.yaml``) and ``key=value`` overrides.
:func:`compose_config` gives the same result as ``hydra.compose`` but composes each group
choice only once per process (a Hydra compose costs 10-100 ms; grafting a cached node and
applying overrides with OmegaConf costs well under one).

Structured schemas (:func:`register_schemas`, Hydra's ConfigStore) type the scenario and estimator configs:
a typo such as ``scenario.nosie=2`` or a value of the wrong type fails here, at compose time,
in one line naming the key and the keys that exist. Range checks (``noise >= 0``...) stay in
the constructors of the objects the configs build.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import importlib
import importlib.util
import inspect
import json
import pickle
import re
import sys
import types
import typing
from collections.abc import Mapping
from dataclasses import field as _field, make_dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional

from omegaconf import MISSING, DictConfig, OmegaConf, flag_override

from magexp import paths
from magexp.errors import MagexpError, raise_if_stopped
from magexp.paths import CONF
from magexp.run import cache
from magexp.run.guard import check_target

GROUPS = ("scenario", "estimator")
PRIMARY = "config"
#: keys that belonged to the simulation command before calibration got its own
CALIBRATE_KEYS = ("task", "data", "out")


# ---------------------------------------------------------------------------------------------
# structured schemas (ConfigStore groups ``schema/scenario`` and ``schema/estimator``)
#
# Every scenario and estimator config is typed. A class's schema is its ``Config`` dataclass (the
# scenarios: beside their classes in magexp/scenarios/), else the dataclass of its constructor's
# typed parameters (:func:`schema_of`: the estimators and their strategy pieces, so a constructor
# and its schema cannot disagree). It is stored under the class's name, and a config names it in
# its defaults list: ``- /schema/estimator/LevenbergMarquardt@_here_``, a nested node of another
# class at its key (``- /schema/estimator/Linear@velocity.inertia``).

_TARGET = re.compile(r"_target_:\s*([A-Za-z_][\w.]*)")


def _typed(hint):
    """``hint`` as OmegaConf types it: ``X | None`` -> ``Optional[X]``, ``list[X]`` -> ``List[X]``,
    ``dict`` -> ``Dict[str, Any]``, a class OmegaConf does not type (a strategy object) -> ``Any``."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        rest = [a for a in args if a is not type(None)]
        inner = _typed(rest[0]) if len(rest) == 1 else Any
        return Optional[inner] if len(rest) < len(args) and inner is not Any else inner
    if origin in (list, List):
        return List[_typed(args[0])] if args else List[Any]
    if hint is dict or origin is dict:
        return Dict[str, Any]
    return hint if hint in (int, float, str, bool) else Any


#: the schemas :func:`schema_of` derives, by name: a derived dataclass lives here, so that it pickles
DERIVED = types.SimpleNamespace()


@functools.cache
def schema_of(cls) -> type:
    """The schema of the configs that build ``cls``: its ``Config`` dataclass if it has one, else a
    dataclass of its constructor's parameters with their annotations (:func:`_typed`) and defaults
    (none: the config must give it), plus ``_target_`` (kept in :data:`DERIVED` as ``<class>Conf``; class names are unique among the configs' classes)."""
    if "Config" in dir(cls):
        return cls.Config
    name = f"{cls.__name__}Conf"
    hints = typing.get_type_hints(cls.__init__)
    fields = [("_target_", str, _field(default=MISSING))]
    for p in list(inspect.signature(cls.__init__).parameters.values())[1:]:
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        default = MISSING if p.default is p.empty else p.default
        kind = _typed(hints.get(p.name, Any))
        if isinstance(default, (list, tuple)):
            fields.append((p.name, kind if kind is not Any else List[Any], _field(default_factory=lambda d=default: list(d))))
        else:
            fields.append((p.name, kind, _field(default=default)))
    schema = make_dataclass(name, fields, namespace={"__doc__": f"Schema of {cls.__module__}.{cls.__qualname__}.",
                                                     "__module__": __name__})
    schema.__qualname__ = f"DERIVED.{name}"
    setattr(DERIVED, name, schema)
    return schema


def schema_classes(group: str) -> list[type]:
    """Every class a ``_target_`` of ``conf/<group>/`` names (nested nodes and base configs included) that
    :func:`magexp.run.guard.check_target` allows, imported: the classes whose schemas are registered."""
    targets = sorted({t for path in (CONF / group).rglob("*.yaml") for t in _TARGET.findall(path.read_text())})
    classes = []
    for target in targets:
        try:
            check_target(group, target)
        except MagexpError:  # not a class magexp may build: its config fails when it is composed, not here
            continue
        module, _, name = target.rpartition(".")
        classes.append(getattr(importlib.import_module(module), name))
    return classes


@functools.cache
def register_schemas() -> dict:
    """Store the schema of every class of :func:`schema_classes` in Hydra's ConfigStore (group
    ``schema/<group>``, named after the class), once; returns ``{name: schema}``."""
    from hydra.core.config_store import ConfigStore

    store, schemas = ConfigStore.instance(), {}
    for group in GROUPS:
        for cls in schema_classes(group):
            schemas[cls.__name__] = schema = schema_of(cls)
            store.store(group=f"schema/{group}", name=cls.__name__, node=schema)
    return schemas


class _Schemas(Mapping):
    """``{name: schema}`` of :func:`register_schemas`, registered on first use."""

    def __getitem__(self, name):
        return register_schemas()[name]

    def __iter__(self):
        return iter(register_schemas())

    def __len__(self):
        return len(register_schemas())


SCHEMAS = _Schemas()


# ---------------------------------------------------------------------------------------------
# values, options, errors

@functools.cache
def _override_parser():
    from hydra.core.override_parser.overrides_parser import OverridesParser

    return OverridesParser.create()


def parse_overrides(overrides: list[str]) -> list:
    """Hydra's parsed overrides, or one MagexpError line."""
    try:
        return _override_parser().parse_overrides(list(overrides))
    except Exception as exc:
        raise MagexpError(f"could not parse the overrides {' '.join(overrides)!r}: "
                          f"{str(exc).splitlines()[0]}") from None


_INT = re.compile(r"[-+]?(0|[1-9][0-9]*)")
_FLOAT = re.compile(r"[-+]?((0|[1-9][0-9]*)\.[0-9]*|\.[0-9]+|(0|[1-9][0-9]*))([eE][-+]?[0-9]+)?")
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_SPECIAL = {"true", "false", "null", "inf", "nan"}


def yaml_value(text: str):
    """A command-line value typed as Hydra's override grammar types it (``2`` -> int,
    ``1e-06`` -> float, ``[1,2]`` -> list, ``null`` -> None, ``a`` -> str).

    Plain integers, decimal floats and identifiers are typed here; anything else (lists,
    quotes, ``inf``, ``null``, interpolations...) by Hydra's parser, which the common case of a
    one-run command then never loads.
    """
    if _INT.fullmatch(text):
        return int(text)
    if _FLOAT.fullmatch(text):
        return float(text)
    if _WORD.fullmatch(text) and text.lower() not in _SPECIAL:
        return text
    return parse_overrides([f"k={text}"])[0].value()


def options(group: str) -> list[str]:
    """Config names available in ``conf/<group>/`` (files directly in it; sub-folders hold bases)."""
    return sorted(p.stem for p in (CONF / group).glob("*.yaml"))


def target_class(group: str, name: str):
    """The class named by ``_target_`` in ``conf/<group>/<name>.yaml`` (imported, not built)."""
    module, _, cls = str(OmegaConf.load(CONF / group / f"{name}.yaml")["_target_"]).rpartition(".")
    return getattr(importlib.import_module(module), cls)


def check_choice(group: str, choice: str) -> None:
    """Fail unless ``conf/<group>/<choice>.yaml`` exists."""
    names = options(group)
    if choice not in names:
        raise MagexpError(f"{group}={choice!r} is not allowed: choose one of {', '.join(names)}")


def _keys_of(cfg: DictConfig, key: str) -> tuple[str, list[str]]:
    """The deepest existing parent of dotted ``key`` and its keys."""
    parts = key.split(".")
    node, path = cfg, []
    for part in parts[:-1]:
        child = node.get(part) if isinstance(node, DictConfig) else None
        if not isinstance(child, DictConfig):
            break
        node, path = child, path + [part]
    return ".".join(path) or "the config", sorted(str(k) for k in node.keys()) if isinstance(node, DictConfig) else []


def unknown_key(cfg: DictConfig, key: str, value: str, config_name: str = PRIMARY) -> MagexpError:
    """The one-line error of an override whose key is not in the config."""
    if config_name == PRIMARY and key.split(".")[0] in CALIBRATE_KEYS:
        return MagexpError(f"{key}={value} is not allowed: the simulation command has no {key.split('.')[0]!r}; "
                           "calibrate a recording with `magexp calibrate data.path=<file> ...`")
    where, keys = _keys_of(cfg, key)
    return MagexpError(f"{key}={value} is not allowed: {where} has no key {key.split('.')[-1]!r} "
                       f"(keys: {', '.join(keys)})")


def _bad_value(key: str, value: str, exc: Exception) -> MagexpError:
    """A value the schema's type refuses: one line naming the key, the value and the type wanted."""
    msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    for name, wanted in (("Integer", "an integer"), ("Float", "a number"), ("Boolean", "true or false")):
        if f"converted to {name}" in msg:
            return MagexpError(f"{key}={value} is not allowed: it must be {wanted}")
    return MagexpError(f"{key}={value} is not allowed: {msg}")


# ---------------------------------------------------------------------------------------------
# composing

def hydra_compose(overrides: tuple[str, ...] = (), config_name: str = PRIMARY, *,
                  with_hydra: bool = False) -> DictConfig:
    """``hydra.compose`` of ``conf/<config_name>.yaml`` (inside or outside an initialised Hydra);
    ``with_hydra``: with the ``hydra`` node (launcher, sweeper, folders), which checks ``hydra.*``
    overrides."""
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    register_schemas()
    try:
        if GlobalHydra.instance().is_initialized():
            return compose(config_name, overrides=list(overrides), return_hydra_config=with_hydra)
        with initialize_config_dir(config_dir=str(CONF), version_base=None):
            return compose(config_name, overrides=list(overrides), return_hydra_config=with_hydra)
    except MagexpError:
        raise
    except Exception as exc:
        chain, cause = [], exc
        while cause is not None and len(chain) < 5:  # Hydra keeps the reason in the cause
            chain.append(str(cause))
            cause = cause.__cause__ or cause.__context__
        lines = [ln.strip() for text in chain for ln in text.splitlines() if ln.strip()]
        detail = "; ".join([lines[0]] + [ln for ln in lines[1:] if "not in" in ln or "Error" in ln
                                          or "could not be converted" in ln][:1]) if lines else type(exc).__name__
        raise MagexpError(f"bad override: {detail}") from None


_SKELETONS: dict = {}  # config name -> the pickled primary config without its group nodes
_NODES: dict = {}  # (config name, group, choice) -> that choice's composed node, pickled
_SEEN: set = set()  # config names composed at least once in this process


def _composed(config_name: str, choices: dict[str, str]) -> DictConfig:
    """A config with these group choices, for the caller to keep.

    A process's first config is Hydra's compose itself (a one-run command composes once and
    copies nothing). From the second on, every new choice is composed by Hydra once and kept
    (the primary config's skeleton and each group's node); configs of known choices are
    then grafted without Hydra from fresh copies of the pieces. The pieces are kept as this
    process's own pickles (never written anywhere): a copy is then an unpickling, 1.3 ms for a
    whole run config where ``copy.deepcopy`` of its pieces took 5 ms (OmegaConf copies node by
    node in Python), and the grafted nodes, fresh already, are set without OmegaConf's copy.
    """
    for group, choice in choices.items():
        check_choice(group, choice)
    wanted = {g: choices.get(g) or _default_choice(config_name, g) for g in GROUPS}
    if config_name in _SKELETONS and all((config_name, g, c) in _NODES for g, c in wanted.items() if c):
        cfg = pickle.loads(_SKELETONS[config_name])
        OmegaConf.set_struct(cfg, False)
        with flag_override(cfg, "no_deepcopy_set_nodes", True):
            for group, choice in wanted.items():
                if choice:
                    cfg[group] = pickle.loads(_NODES[(config_name, group, choice)])
        OmegaConf.set_struct(cfg, True)
        return cfg
    cfg = _stored_compose(config_name, choices)
    if config_name in _SEEN:  # more than one config in this process: keep the pieces
        kept = copy.deepcopy(cfg)
        OmegaConf.set_struct(kept, False)
        for group, choice in wanted.items():
            if choice and group in kept:
                node = kept[group]
                del kept[group]
                node._set_parent(None)  # pickled alone: a node keeps its parent, the whole config, after del
                _NODES.setdefault((config_name, group, choice), pickle.dumps(node))
        OmegaConf.set_struct(kept, True)
        _SKELETONS.setdefault(config_name, pickle.dumps(kept))
    _SEEN.add(config_name)
    return cfg


def _compose_key(config_name: str, choices: dict[str, str]) -> str:
    """Key of a composed config on disk: the choices, and the size and time of every config file,
    of this module (the schemas) and of the Hydra and OmegaConf installed."""
    h = hashlib.sha256(json.dumps([config_name, sorted(choices.items()), OmegaConf.__module__]).encode())
    files = sorted(CONF.rglob("*.yaml")) + [Path(__file__)]
    for name in ("hydra", "omegaconf"):
        spec = importlib.util.find_spec(name)
        files.append(Path(spec.origin) if spec and spec.origin else Path(name))
    for path in files:
        try:
            st = path.stat()
            h.update(f"{path}:{st.st_size}:{st.st_mtime_ns};".encode())
        except OSError:
            h.update(f"{path}:missing;".encode())
    return h.hexdigest()[:32]


def _stored_compose(config_name: str, choices: dict[str, str]) -> DictConfig:
    """Hydra's compose of these choices, kept on disk (:func:`magexp.paths.composed_configs`) under a key of
    every config file, so that a command whose choices were composed before needs no Hydra
    compose at all (the largest part of a one-run command's start-up: ``--cfg job`` takes less than
    half the CPU time with it, measured beside composing without it).

    An entry is data (:func:`magexp.run.cache.pack`, kind ``config``): the config's unresolved
    container and the schema of each node that has one (:data:`SCHEMAS`), checked when read (its
    key, kind and digest); it is kept only when it gives back the very config Hydra composed. An
    invalid entry is composed again (said once)."""
    root = paths.composed_configs()
    key = _compose_key(config_name, choices)
    path = root / f"{key}.json"
    try:
        return config_from(cache.read(path, key, "config"))
    except FileNotFoundError:
        pass
    except (OSError, cache.InvalidEntry) as exc:
        _say_once(f"note: composed-config cache {root}: an entry is not valid ({exc}); composed again")
    cfg = hydra_compose(tuple(f"{g}={c}" for g, c in choices.items()), config_name)
    entry = {"config": OmegaConf.to_container(cfg, resolve=False),
             "schemas": {name: schema for name in cfg if (schema := _schema_of(cfg[name]))}}
    try:
        if OmegaConf.to_yaml(config_from(entry)) == OmegaConf.to_yaml(cfg):
            _PENDING.append((path, cache.pack(key, "config", entry), root))  # kept once the overrides pass
    except cache.InvalidEntry:  # a config this format cannot hold exactly: composed every time
        pass
    return cfg


_PENDING: list = []  # (path, packed entry, cache folder) composed by Hydra, not yet kept on disk


def _keep_composed() -> None:
    """Keep the configs Hydra composed on disk (:func:`_stored_compose`), after the overrides of the
    command were applied without error: a refused command writes no composed config."""
    while _PENDING:
        path, data, root = _PENDING.pop()
        try:
            cache.write(path, data, root)
        except OSError:  # a read-only cache: compose every time
            pass


def _schema_of(node) -> str | None:
    """The name of the :data:`SCHEMAS` entry that types ``node``, if any."""
    kind = OmegaConf.get_type(node) if isinstance(node, DictConfig) else None
    return next((name for name, schema in SCHEMAS.items() if schema is kind), None)


def config_from(entry) -> DictConfig:
    """The config an entry of :func:`_stored_compose` holds: its container, each typed node merged
    onto its schema (so its keys and value types are checked as Hydra's are), in struct mode."""
    if not (isinstance(entry, dict) and isinstance(entry.get("config"), dict) and isinstance(entry.get("schemas"), dict)
            and all(name in entry["config"] and schema in SCHEMAS for name, schema in entry["schemas"].items())):
        raise cache.InvalidEntry("not a composed config")
    try:
        cfg = OmegaConf.create(entry["config"])
        for name, schema in entry["schemas"].items():
            cfg[name] = OmegaConf.merge(OmegaConf.structured(SCHEMAS[schema]), entry["config"][name])
    except Exception as exc:  # OmegaConf refuses what its schema does not allow
        raise_if_stopped()  # ...or it swallowed a SIGTERM that arrived during the merge
        raise cache.InvalidEntry(f"not a composed config: {type(exc).__name__}") from None
    OmegaConf.set_struct(cfg, True)
    return cfg


_SAID: list = []


def _say_once(line: str) -> None:
    """Print ``line`` if this process has said nothing about the composed-config cache yet."""
    if not _SAID:
        print(line, file=sys.stderr)
    _SAID.append(line)


@functools.cache
def _default_choice(config_name: str, group: str) -> str | None:
    """The primary config's default option of ``group`` (its defaults list)."""
    defaults = OmegaConf.load(CONF / f"{config_name}.yaml").get("defaults", [])
    for entry in defaults:
        if isinstance(entry, DictConfig) and group in entry:
            return str(entry[group])
    return None


def compose_config(overrides: list[str] | tuple[str, ...] = (), *, config_name: str = PRIMARY) -> DictConfig:
    """The run config of ``overrides``, as Hydra composes it, or one MagexpError line.

    The config-group choices (``scenario=...``, ``estimator=...``) are composed by Hydra once
    per process; their nodes are grafted onto the primary config and the ``key=value``
    overrides applied with OmegaConf in struct mode (an unknown key, or a value the schema's
    type refuses, is an error naming the key and what exists). Anything beyond ``group=choice``
    and ``key=value`` (``+key``, ``~key``, ``hydra.*``, ``group/sub=...``) goes to Hydra itself.
    The result is the caller's own (a fresh copy).
    """
    choices, values = {}, []
    for ov in overrides:
        key, _, value = ov.partition("=")
        if key in GROUPS:
            choices[key] = value
        elif key.startswith(("+", "~", "hydra")) or "/" in key or "@" in key:
            for group, choice in choices.items():
                check_choice(group, choice)
            return hydra_compose(tuple(overrides), config_name)
        else:
            values.append((key, value))
    cfg = _composed(config_name, choices)
    for key, value in values:
        if OmegaConf.select(cfg, key, default="__missing__") == "__missing__":
            raise unknown_key(cfg, key, value, config_name)
        typed = yaml_value(value)
        try:
            OmegaConf.update(cfg, key, typed, merge=False)
        except MagexpError:
            raise
        except Exception as exc:  # the schema refused the value's type
            if not (isinstance(typed, float) and typed.is_integer()):
                raise _bad_value(key, value, exc) from None
            try:  # 1e8 for an integer key means 100000000
                OmegaConf.update(cfg, key, int(typed), merge=False)
            except Exception:
                raise _bad_value(key, value, exc) from None
    _keep_composed()
    return cfg


def resolved(cfg: DictConfig) -> dict:
    """The plain resolved container of a run config (``hydra`` node left out): what a run reads."""
    out = OmegaConf.to_container(cfg, resolve=True)
    out.pop("hydra", None)
    return out
