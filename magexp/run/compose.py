"""The one place that composes configurations: the CLI, sweeps, reproduce, bench, calibrate and the tests.

A run config is Hydra's composition of ``conf/config.yaml`` with one choice per config group
(``conf/scenario/*.yaml``, ``conf/estimator/*.yaml``) and ``key=value`` overrides:
:func:`compose_config` is ``hydra.compose``, in two steps. Hydra composes each group choice once per
process, and a set of choices takes each group's node from its own choice's composition (no config
of a group writes outside its package); a set with a ``+key``, ``~key`` or ``hydra.*`` override is
composed whole, once. Each ``key=value`` override is then applied to a copy with OmegaConf's update
against the composed schema (:func:`apply_overrides`), as ``hydra.compose`` applies it after the
defaults. The planning of ``make reproduce`` composes each scenario and each estimator once, not each
of its sets of choices (``docs/measurements.md``, "Speed twins").

Structured schemas (:func:`register_schemas`, Hydra's ConfigStore) type the scenario and estimator configs:
a typo such as ``scenario.nosie=2`` or a value of the wrong type fails here, at compose time,
in one line naming the key and the keys that exist. Range checks (``noise >= 0``...) stay in
the constructors of the objects the configs build.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import importlib
import importlib.util
import inspect
import re
import types
import typing
from collections.abc import Mapping
from dataclasses import field as _field, make_dataclass
from typing import Any, Dict, List, Optional

from hydra import compose, initialize_config_dir
from hydra.core.config_store import ConfigStore
from hydra.core.global_hydra import GlobalHydra
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override, OverrideType
from hydra.utils import get_class
from omegaconf import MISSING, DictConfig, OmegaConf

from magexp.errors import MagexpError, raise_if_stopped
from magexp.paths import CONF
from magexp.run.derived import Derived
from magexp.run.keys import check_override
from magexp.run.override_errors import PRIMARY, bad_value, unknown_key
from magexp.run.targets import check_target

GROUPS = ("scenario", "estimator")


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
DERIVED = Derived(lambda: register_schemas())  # a lambda: register_schemas is defined below


@functools.cache
def schema_of(cls) -> type:
    """The schema of the configs that build ``cls``: its ``Config`` dataclass if it has one, else a
    dataclass of its constructor's parameters with their annotations (:func:`_typed`) and defaults
    (none: the config must give it), plus ``_target_`` (kept in :data:`DERIVED` as ``<class>Conf``; class names are unique among the configs' classes).
    """
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
    :func:`magexp.run.targets.check_target` allows, imported: the classes whose schemas are registered."""
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
def register_schemas(groups: tuple[str, ...] = GROUPS) -> dict:
    """Store the schema of every class of :func:`schema_classes` in Hydra's ConfigStore (group
    ``schema/<group>``, named after the class)."""
    store, schemas = ConfigStore.instance(), {}
    for group in groups:
        for cls in schema_classes(group):
            schemas[cls.__name__] = schema = schema_of(cls)
            store.store(group=f"schema/{group}", name=cls.__name__, node=schema)
    return schemas


# ---------------------------------------------------------------------------------------------
# values, options, errors

@functools.cache
def _override_parser():
    """Hydra's override parser, made once per process."""
    return OverridesParser.create()


@functools.lru_cache(maxsize=4096)
def _parsed(text: str) -> Override:
    """Hydra's parse of one override, kept (an :class:`Override` is not changed by its readers)."""
    return _override_parser().parse_overrides([text])[0]


def parse_overrides(overrides: list[str], *, parser: OverridesParser | None = None) -> list[Override]:
    """Hydra's parsed overrides (its grammar types every value), or one MagexpError line."""
    try:
        if parser is None:  # each override parsed once per process: the planning of make reproduce reads 1,578
            return [_parsed(text) for text in overrides]
        return parser.parse_overrides(list(overrides))
    except Exception as exc:
        raise MagexpError(f"could not parse the overrides {' '.join(overrides)!r}: "
                          f"{str(exc).splitlines()[0]}") from None


def override_value(text: str):
    """A command-line value as Hydra's override grammar types it (``2`` -> int, ``1e-06`` -> float,
    ``[1,2]`` -> list, ``null`` -> None, ``a`` -> str)."""
    return parse_overrides([f"k={text}"])[0].value()


def options(group: str) -> list[str]:
    """Config names available in ``conf/<group>/`` (files directly in it; sub-folders hold bases)."""
    return sorted(p.stem for p in (CONF / group).glob("*.yaml"))


def target_class(group: str, name: str, *, config_name: str = PRIMARY):
    """The class named by ``_target_`` in the composed ``conf/<group>/<name>.yaml`` (imported, not built)."""
    return get_class(compose_config([f"{group}={name}"], config_name=config_name)[group]._target_)


def check_choice(group: str, choice: str) -> None:
    """Fail unless ``conf/<group>/<choice>.yaml`` exists."""
    names = options(group)
    if choice not in names:
        raise MagexpError(f"{group}={choice!r} is not allowed: choose one of {', '.join(names)}")


# ---------------------------------------------------------------------------------------------
# composing

@functools.cache
def primary_groups(config_name: str) -> tuple[str, ...]:
    """The groups of :data:`GROUPS` that ``conf/<config_name>.yaml``'s defaults list chooses from: the schemas its
    composing needs (``calibrate``: the estimators only, which spares importing every scenario class)."""
    defaults = OmegaConf.load(CONF / f"{config_name}.yaml").get("defaults") or []
    chosen = {key for item in defaults if isinstance(item, Mapping) or OmegaConf.is_dict(item) for key in item}
    return tuple(g for g in GROUPS if g in chosen)


@contextlib.contextmanager
def _hydra(config_name: str = PRIMARY):
    """Hydra initialised on ``conf/`` with the schemas ``config_name`` composes (:func:`primary_groups`; the caller's
    own initialisation if Hydra runs already: a job of Hydra's own launchers)."""
    register_schemas(primary_groups(config_name))
    if GlobalHydra.instance().is_initialized():
        yield GlobalHydra.instance()
    else:
        with initialize_config_dir(config_dir=str(CONF), version_base=None):
            yield GlobalHydra.instance()


def config_loader():
    """Hydra's config loader on ``conf/`` (it lists a config group's options, which a ``glob(...)`` sweep reads)."""
    with _hydra() as hydra:
        return hydra.config_loader()


def hydra_compose(overrides: tuple[str, ...] = (), config_name: str = PRIMARY, *,
                  with_hydra: bool = False) -> DictConfig:
    """``hydra.compose`` of ``conf/<config_name>.yaml``, or one MagexpError line; ``with_hydra``: with
    the ``hydra`` node (launcher, sweeper, folders), which checks ``hydra.*`` overrides."""
    try:
        with _hydra(config_name):
            return compose(config_name, overrides=list(overrides), return_hydra_config=with_hydra)
    except MagexpError:
        raise
    except Exception as exc:
        raise_if_stopped()  # a SIGTERM that OmegaConf turned into an error of its own stops the command
        chain, cause = [], exc
        while cause is not None and len(chain) < 5:  # Hydra keeps the reason in the cause
            chain.append(str(cause))
            cause = cause.__cause__ or cause.__context__
        lines = [ln.strip() for text in chain for ln in text.splitlines() if ln.strip()]
        detail = "; ".join([lines[0]] + [ln for ln in lines[1:] if "not in" in ln or "Error" in ln
                                          or "could not be converted" in ln][:1]) if lines else type(exc).__name__
        raise MagexpError(f"bad override: {detail}") from None


def _is_value(override: Override) -> bool:
    """Whether Hydra applies ``override`` after composing the defaults (``key=value`` of a config key),
    rather than while composing them (a config group's choice, ``+key``, ``~key``, ``hydra.*``)."""
    key = override.key_or_group
    return (override.type == OverrideType.CHANGE and override.package is None and "/" not in key
            and not key.startswith("hydra") and key not in _groups())


@functools.cache
def _groups() -> frozenset:
    """The config groups of ``conf/`` (its folders)."""
    return frozenset(p.name for p in CONF.iterdir() if p.is_dir())


def apply_overrides(cfg: DictConfig, overrides: list[str], *, config_name: str = PRIMARY) -> DictConfig:
    """Apply ``key=value`` overrides to ``cfg`` (changed in place, and returned) as Hydra's override step does
    (Hydra's parser types each value, OmegaConf's update checks it against the config's schema);
    ``config_name``, the primary config ``cfg`` was composed from, words the error of an unknown key.

    Raises
    ------
    MagexpError
        One line naming the key and what exists, for an unknown key or a value the schema's type refuses."""
    return _apply(cfg, parse_overrides(overrides), config_name)


def _apply(cfg: DictConfig, overrides: list[Override], config_name: str) -> DictConfig:
    """:func:`apply_overrides` of overrides parsed already."""
    for override in overrides:
        key = override.key_or_group
        if override.is_sweep_override():
            raise MagexpError(f"{override.input_line} is not allowed: it lists several values (a sweep); give one "
                              "value, or a list as [a,b]")
        text = override.get_value_element_as_str()
        if OmegaConf.select(cfg, key, default="__missing__") == "__missing__":
            raise unknown_key(cfg, key, text, config_name)
        try:  # text for a number, an empty name, a list's shape
            check_override(cfg, key, override.value(), text)
        except MagexpError:
            raise_if_stopped()  # a stop received meanwhile ends the command as the signal asks
            raise
        try:
            _update(cfg, override)
        except Exception as exc:  # the schema refused the value's type
            raise_if_stopped()  # ...or OmegaConf swallowed a SIGTERM that arrived during the update
            if not _assigned(cfg, key, override.value()):
                raise bad_value(key, text, exc) from None
    return cfg


def _update(cfg: DictConfig, override: Override) -> None:
    """Hydra's override step for a ``key=value`` of a key ``cfg`` has: OmegaConf's merging update (the
    schema's type checks the value), a ``key@package`` refused as Hydra refuses it."""
    if override.package is not None:
        raise ValueError(f"Override {override.input_line} looks like a config group override, but config group "
                         f"'{override.key_or_group}' does not exist.")
    OmegaConf.update(cfg, override.key_or_group, override.value(), merge=True)


def _assigned(cfg: DictConfig, key: str, value) -> bool:
    """Whether OmegaConf's assignment takes a value that Hydra's merge refused: integers in a nested list
    of floats (OmegaConf's merge checks a nested list's element type before converting it:
    ``scenario.errors.soft_iron=[[1,0,0],[0,1,0],[0,0,1]]``), or a float with an integer value for an
    integer key (``scenario.n_readings=1e8`` is 100000000)."""
    whole = isinstance(value, float) and value.is_integer()
    for candidate in (value, int(value)) if whole else (value,):
        try:
            OmegaConf.update(cfg, key, candidate, merge=False)
            return True
        except Exception:
            raise_if_stopped()
    return False


_COMPOSED: dict = {}  # (config name, the overrides Hydra composes with) -> Hydra's config, never handed out
_OWN: dict = {}  # (config name, group, choice) -> whether the choice writes only its group's node (_own_package)


def compose_config(overrides: list[str] | tuple[str, ...] = (), *, config_name: str = PRIMARY) -> DictConfig:
    """The config of ``overrides``, as ``hydra.compose`` composes it.

    Hydra composes the defaults of the config-group choices and of the overrides it applies while
    composing (``+key``, ``~key``, ``hydra.*``) once per process; a copy then takes the ``key=value``
    overrides through :func:`apply_overrides` (Hydra's step after the defaults). ``config_name``: the
    primary config, ``config`` (a run) or ``calibrate``. The config returned is in struct mode, the caller's own.

    Raises
    ------
    MagexpError
        One line for an unknown choice or key, or a value the schema refuses."""
    parsed = parse_overrides(list(overrides))
    defaults = tuple(ov.input_line for ov in parsed if not _is_value(ov))
    if (config_name, defaults) not in _COMPOSED:
        for ov in parsed:
            if ov.key_or_group in GROUPS and not ov.is_sweep_override():
                check_choice(ov.key_or_group, ov.get_value_element_as_str())
        choices = _choices([ov for ov in parsed if not _is_value(ov)])
        separate = choices and all(_own_package(config_name, group, choice) for group, choice in choices.items())
        _COMPOSED[config_name, defaults] = (_assembled(choices, config_name) if separate
                                             else hydra_compose(defaults, config_name))
    cfg = copy.deepcopy(_COMPOSED[config_name, defaults])
    return _apply(cfg, [ov for ov in parsed if _is_value(ov)], config_name)


def _choices(parsed: list[Override]) -> dict | None:
    """``{group: choice}`` when ``parsed`` holds only one plain choice per group of :data:`GROUPS`, else None."""
    plain = all(ov.key_or_group in GROUPS and ov.type == OverrideType.CHANGE and ov.package is None
                and not ov.is_sweep_override() for ov in parsed)
    choices = {ov.key_or_group: ov.get_value_element_as_str() for ov in parsed} if plain else {}
    return choices if len(choices) > 1 and len(choices) == len(parsed) else None


def _own_package(config_name: str, group: str, choice: str) -> bool:
    """Whether ``group=choice`` changes nothing of the default composition outside its group's node: then its node
    is its whole contribution, and :func:`_assembled` may take it into a set of choices."""
    def apart(cfg):
        return {k: v for k, v in OmegaConf.to_container(cfg, resolve=False).items() if k != group}
    if (config_name, group, choice) not in _OWN:
        _OWN[config_name, group, choice] = (apart(_group_composed(config_name, group, choice))
                                            == apart(_group_composed(config_name)))
    return _OWN[config_name, group, choice]


def _assembled(choices: dict, config_name: str) -> DictConfig:
    """The composition of several group choices from one Hydra composition per choice, each of which writes only
    its own group's node (:func:`_own_package`): the first group's composition takes each other group's node from
    that group's own (``make reproduce``: each scenario and each estimator composed once)."""
    (first, choice), *rest = choices.items()
    cfg = copy.deepcopy(_group_composed(config_name, first, choice))
    for group, choice in rest:
        cfg[group] = _group_composed(config_name, group, choice)[group]
    return cfg


def _group_composed(config_name: str, group: str | None = None, choice: str | None = None) -> DictConfig:
    """Hydra's composition of the single choice ``group=choice`` (None: the defaults), once per process (never
    handed out)."""
    key = (config_name, (f"{group}={choice}",) if group else ())
    if key not in _COMPOSED:
        _COMPOSED[key] = hydra_compose(key[1], config_name)
    return _COMPOSED[key]


def resolved(cfg: DictConfig) -> dict:
    """The plain resolved container of a run config (``hydra`` node left out): what a run reads."""
    out = OmegaConf.to_container(cfg, resolve=True)
    out.pop("hydra", None)
    return out


@functools.cache
def estimator_label(name: str) -> str:
    """An estimator's name in words (row labels, figure axes)."""
    if name not in options("estimator"):
        return name
    label = OmegaConf.load(CONF / "estimator" / f"{name}.yaml").get("label")
    return str(label or getattr(target_class("estimator", name), "label", "") or name)
