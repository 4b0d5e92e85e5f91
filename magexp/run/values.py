"""The values of a resolved run config that no constructor checks (:func:`check_run_values`): every number
finite and of magnitude <= :data:`magexp.errors.LARGEST`, the geomagnetic field's ranges, ``write_history``
a boolean. Every refusal is a :class:`~magexp.errors.MagexpError` of one line naming the key and what is allowed.
"""

from __future__ import annotations

from magexp.errors import MagexpError
from magexp.run.keys import check_number

#: The geomagnetic field's ranges (degrees): inclination from the horizontal, declination from north.
INCLINATION = (-90.0, 90.0)
DECLINATION = (-180.0, 360.0)


def _numbers(node, where: str):
    """``(dotted key, number)`` of every number in a plain config container."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _numbers(v, f"{where}.{k}" if where else str(k))
    elif isinstance(node, (list, tuple)):
        for i, v in enumerate(node):
            yield from _numbers(v, f"{where}[{i}]")
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield where, node


def check_run_values(plain: dict) -> None:
    """Values of a resolved run config that no constructor checks, refused in one line.

    * every number of ``scenario`` and ``estimator`` finite, of magnitude <= :data:`magexp.errors.LARGEST`
      (``hard_iron=[1e308,0,0]`` would overflow the simulation into a singular matrix), zero or of
      magnitude >= :data:`magexp.run.keys.SMALLEST` (:func:`magexp.run.keys.check_number`);
    * ``scenario.field``: a vector not zero; ``total`` > 0, ``inclination`` in :data:`INCLINATION`,
      ``declination`` in :data:`DECLINATION` (degrees);
    * ``write_history``: true or false."""
    for group in ("scenario", "estimator"):
        for key, value in _numbers(plain.get(group) or {}, group):
            check_number(value, key)
    _check_field((plain.get("scenario") or {}).get("field"))
    history = plain.get("write_history", True)
    if not isinstance(history, bool):
        raise MagexpError(f"write_history={history!r} is not allowed: choose true or false")


def _check_field(field) -> None:
    """``scenario.field``: a vector not zero, or ``total`` > 0 and the angles in their ranges."""
    if isinstance(field, list) and not any(v != 0 for v in field if isinstance(v, (int, float))):
        raise MagexpError(f"scenario.field={field!r} is not allowed: the field vector must not be zero (nT)")
    if isinstance(field, dict):
        total = field.get("total")
        if isinstance(total, (int, float)) and not total > 0:
            raise MagexpError(f"scenario.field.total={total!r} is not allowed: the field's total intensity must be "
                              "a number > 0 (nT)")
        for name, (lo, hi) in (("inclination", INCLINATION), ("declination", DECLINATION)):
            value = field.get(name)
            if isinstance(value, (int, float)) and not lo <= value <= hi:
                raise MagexpError(f"scenario.field.{name}={value!r} is not allowed: it must be in [{lo:g}, {hi:g}] "
                                  "degrees")
