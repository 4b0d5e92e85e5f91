"""Readable labels of summary rows: estimator, quantity and the settings that tell a cell from its
artifact's others (:func:`label_of`), e.g. ``IPSO final RMS, exp1, A = 2 nT``.
"""

from __future__ import annotations

import re

from magexp.run.compose import estimator_label


#: readable names of quantities in row labels (others are shown as they are)
QUANTITY_NAMES = {"final_rms": "final RMS", "converged_fraction": "converged fraction",
                  "improvement_ratio": "final RMS ratio", "fit_rms": "fit RMS"}


def label_of(spec, cells: list[dict], ci: int, quantity: str, estimator: str, prefix: str = "") -> str:
    """A readable row label: estimator, quantity and the settings that tell this cell from the
    artifact's others (``plot.labels`` names a key; a trailing ``(unit)`` moves after the value;
    scenario names lose their paper prefix), e.g. ``IPSO final RMS, exp1, A = 2 nT``.
    """
    cell = cells[ci] if ci < len(cells) else {}
    varying = [k for k in cell if k != "estimator" and len({str(c.get(k)) for c in cells}) > 1]
    names = dict(spec.plot.get("labels", {}) or {}) if spec.plot is not None else {}
    parts = [_setting_text(key, str(cell[key]), names) for key in varying]
    head = " ".join(p for p in (prefix or estimator_label(estimator),
                                QUANTITY_NAMES.get(quantity, quantity)) if p)
    return ", ".join([head, *parts])


def _setting_text(key: str, value: str, names: dict) -> str:
    """One setting of a row label: a scenario by its name without the paper prefix
    (``yuan2018_mode1`` -> ``mode1``), any other key as ``name = value unit`` (:func:`_name_and_unit`)."""
    if key == "scenario":
        return re.sub(r"^[a-z]+\d{4}_", "", value).replace("_", " ")
    name, unit = _name_and_unit(str(names.get(key, key.split(".")[-1].replace("_", " "))))
    return f"{name} = {value}" + (f" {unit}" if unit else "")


def _name_and_unit(name: str) -> tuple[str, str]:
    """A setting's name split from a trailing ``(unit)`` of at most 6 characters; a name of several
    words ending in a symbol of at most 2 letters becomes the symbol (``noise amplitude A`` -> ``A``)."""
    unit = ""
    m = re.match(r"^(.*?)\s*\(([^()]*)\)$", name)
    if m and len(m.group(2)) <= 6:
        name, unit = m.group(1), m.group(2)
    words = name.split()
    if words and len(words[-1]) <= 2 and len(words) > 1:  # "noise amplitude A" -> "A"
        name = words[-1]
    return name, unit
