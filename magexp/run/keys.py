"""Every key checked by its schema, whatever path it comes by: the command line of a run, a sweep's jobs and
``magexp calibrate`` (issue 41).

The rules are the schemas', applied to every key of every config rather than key by key:

* :func:`check_duplicates`: a key given twice on one command line is refused (Hydra would keep the last
  silently), naming both;
* :func:`check_override`: a ``key=value`` override against the node it changes in a composed run config
  (:func:`magexp.run.compose.apply_overrides` calls it): no empty text (``objective=``), no text where the
  schema types a number or a flag (``scenario.noise='1'``, which OmegaConf would convert), and a list of the
  shape of the key's default (``scenario.window=[0,0,0]`` for a ``[start, end]``);
* :func:`check_number`: every number finite, of magnitude at most :data:`magexp.errors.LARGEST`, and either
  zero or of magnitude at least :data:`SMALLEST` (``estimator.sigma0=1e-320``, a subnormal, reaches no
  constructor's ``> 0``: it is positive, yet a step of it underflows to zero);
* :func:`check_schema`: a plain config (``conf/calibrate.yaml``'s) against the dataclass that types it
  (:class:`magexp.calibration.options.CalibrateOptions`): each value's type, a number by :func:`check_number`,
  a text non-empty, a pair a list of two.

Every refusal is one :class:`~magexp.errors.MagexpError` line naming the key, the value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import typing

from omegaconf import BooleanNode, DictConfig, FloatNode, IntegerNode, ListConfig, OmegaConf

from magexp.errors import LARGEST, MagexpError, check_positive_int

#: the smallest magnitude a non-zero number of a config may have: products of a few such numbers stay far above
#: float64's smallest normal number (2.2e-308), below which a step, a scale or a limit silently becomes zero
SMALLEST = 1e-100

#: the largest seed, for every command and the API alike: the bound of every integer key of a command line
#: (:data:`LARGEST`), so a seed that works in Python works on the command line (numpy takes any integer >= 0)
MAX_SEED = int(LARGEST)


def check_seed(seed, name: str = "seed") -> int:
    """``seed`` as an int in ``[0, MAX_SEED]`` (not a bool, not a string), else one line naming ``name``: the
    one seed check of the command line and the API."""
    seed = check_positive_int(seed, name, minimum=0)
    if seed > MAX_SEED:
        raise MagexpError(f"{name}={seed} is not allowed: it must be an integer in [0, {LARGEST:g}]")
    return seed


def check_duplicates(overrides: list[str]) -> None:
    """Refuse a key given twice (``scenario.noise=1 scenario.noise=2``, ``+k`` and ``k`` alike), in one line.

    Raises
    ------
    MagexpError
        Naming the key and both values."""
    seen = {}
    for ov in overrides:
        key = ov.partition("=")[0].lstrip("+~")
        if key in seen:
            raise MagexpError(f"{ov} is not allowed: {key} given twice ({seen[key]} {ov}); give each key once")
        seen[key] = ov


def check_number(value, key: str, *, integer: bool = False) -> None:
    """Refuse a number that is not finite, larger than :data:`LARGEST` or, not zero, smaller than
    :data:`SMALLEST` in magnitude; with ``integer``, one that is not a whole number.

    Raises
    ------
    MagexpError
        One line naming the key, the value and the range allowed."""
    wanted = "an integer" if integer else "a number"
    if isinstance(value, float) and (not math.isfinite(value) or integer and not value.is_integer()):
        raise MagexpError(f"{key}={value!r} is not allowed: it must be {wanted}, finite")
    if abs(value) > LARGEST:
        raise MagexpError(f"{key}={value!r} is not allowed: it must be {wanted} of magnitude <= {LARGEST:g}")
    if value != 0 and abs(value) < SMALLEST:
        raise MagexpError(f"{key}={value!r} is not allowed: it must be 0 or of magnitude >= {SMALLEST:g} (smaller "
                          "numbers underflow to zero in the computation)")


def _is_number(value) -> bool:
    """Whether ``value`` is an int or a float (not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def shape(value) -> tuple | None:
    """The shape of a list of numbers, or a nested list of them (``[[1,0],[0,1]]``: ``(2, 2)``); None for
    anything else (a ragged list, a list of texts or mappings, a number)."""
    if not isinstance(value, (list, tuple)) or not value:
        return None
    if all(_is_number(v) for v in value):
        return (len(value),)
    inner = {shape(v) for v in value}
    return (len(value), *inner.pop()) if len(inner) == 1 and None not in inner else None


def _node(cfg: DictConfig, key: str):
    """The OmegaConf node of dotted ``key`` in ``cfg`` (None when its parent is not a mapping)."""
    parent_key, _, last = key.rpartition(".")
    parent = OmegaConf.select(cfg, parent_key) if parent_key else cfg
    return parent._get_node(last) if isinstance(parent, DictConfig) and last in parent else None


def check_override(cfg: DictConfig, key: str, value, text: str) -> None:
    """A ``key=value`` override checked against the node of ``cfg`` it changes, before it is applied.

    Raises
    ------
    MagexpError
        An empty text, a text for a number or a flag, or a list of another shape than the key's."""
    if isinstance(value, str) and not value.strip():
        raise MagexpError(f"{key}={text!r} is not allowed: give a value (null for none)")
    node = _node(cfg, key)  # typed by a schema (an untyped key's value is checked by its own check)
    if isinstance(value, str) and isinstance(node, BooleanNode):
        raise MagexpError(f"{key}={value!r} is not allowed: it must be true or false, not a text")
    if isinstance(value, str) and isinstance(node, (FloatNode, IntegerNode)):
        wanted = "an integer" if isinstance(node, IntegerNode) else "a number"
        raise MagexpError(f"{key}={text} is not allowed: it must be {wanted}, not a text")
    if isinstance(node, ListConfig) and isinstance(value, list):
        default = OmegaConf.to_container(node, resolve=True) if not node._is_missing() else None
        wanted = shape(default)
        if wanted is not None and shape(value) != wanted:
            size = " x ".join(map(str, wanted))
            raise MagexpError(f"{key}={text} is not allowed: it must be {size} numbers, as {default}")


# ---------------------------------------------------------------------------------------------
# a plain config against its dataclass schema (conf/calibrate.yaml's)

def _kind(hint) -> tuple[object, bool]:
    """``(type, optional)`` of a schema field's hint (``float | None``: ``(float, True)``)."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        rest = [a for a in typing.get_args(hint) if a is not type(None)]
        return (rest[0] if len(rest) == 1 else typing.Any), len(rest) < len(typing.get_args(hint))
    return hint, False


@functools.cache
def _hints(schema) -> dict:
    """The resolved type hints of a dataclass schema."""
    return typing.get_type_hints(schema)


def check_value(value, hint, key: str) -> None:
    """``value`` of ``key`` checked against its schema type ``hint``: None only where the type allows it, a flag
    true or false, a number by :func:`check_number`, a text a non-empty text (or a number, read as its digits),
    a pair a list of its length, each item by its type.

    Raises
    ------
    MagexpError
        One line naming the key, the value and what is allowed."""
    kind, optional = _kind(hint)
    if value is None:
        if not optional:
            raise MagexpError(f"{key}=null is not allowed: give a value ({getattr(kind, '__name__', kind)})")
        return
    _check_scalar(value, kind, key, optional)
    if typing.get_origin(kind) is tuple:
        items = typing.get_args(kind)
        if not isinstance(value, (list, tuple)) or len(value) != len(items):
            raise MagexpError(f"{key}={value!r} is not allowed: it must be a list of {len(items)} numbers")
        for i, (item, item_hint) in enumerate(zip(value, items)):
            check_value(item, item_hint, f"{key}[{i}]")


def _check_scalar(value, kind, key: str, optional: bool) -> None:
    """``value`` (not None) of a flag, number or text key by :func:`check_value`'s rules."""
    if kind is bool and not isinstance(value, bool):
        raise MagexpError(f"{key}={value!r} is not allowed: it must be true or false")
    if kind in (int, float):
        if not _is_number(value):
            raise MagexpError(f"{key}={value!r} is not allowed: it must be {'an integer' if kind is int else 'a number'}")
        check_number(value, key, integer=kind is int)
    if kind is str and (not isinstance(value, (str, int, float)) or isinstance(value, str) and not value.strip()):
        raise MagexpError(f"{key}={value!r} is not allowed: it must be a non-empty text{' (or null)' if optional else ''}")


def check_schema(node: dict, schema, prefix: str = "") -> None:
    """Every key of the plain config ``node`` that ``schema`` (a dataclass, its groups dataclasses) types,
    checked by :func:`check_value`; a group given as anything but a mapping is refused.

    Raises
    ------
    MagexpError
        One line for the first key its schema refuses."""
    hints = _hints(schema)
    for f in dataclasses.fields(schema):
        if f.name not in node:
            continue
        value, hint = node[f.name], hints[f.name]
        if dataclasses.is_dataclass(hint):
            if not isinstance(value, dict):
                raise MagexpError(f"{prefix}{f.name}={value!r} is not allowed: it is a group of keys "
                                  f"({prefix}{f.name}.<key>=...)")
            check_schema(value, hint, f"{prefix}{f.name}.")
        else:
            check_value(value, hint, prefix + f.name)
