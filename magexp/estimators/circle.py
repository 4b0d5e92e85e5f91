"""The Circle chaotic map of Ding 2024's initialiser (sec 2.2.3, eq 15), in numpy; its numba twin is
:func:`magexp.estimators._compiled.circle_sequence`, which takes its steps from here."""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError


def printed_step(z):
    """Ding 2024 eq 15 as printed (see :func:`circle_map`)."""
    return np.mod(2.0 * z + 0.2 - 0.7 / (2 * np.pi) * np.cos(2 * np.pi * z + 0.5 * np.pi), 1.0)


def usual_step(z):
    """The standard Circle map (see :func:`circle_map`)."""
    return np.mod(z + 0.2 - 0.5 / (2 * np.pi) * np.sin(2 * np.pi * z), 1.0)


FORMS = {"printed": printed_step, "usual": usual_step}


def circle_map(z: np.ndarray, form: str = "printed") -> np.ndarray:
    """One step of the Circle chaotic map, element-wise on ``z`` in [0, 1): ``printed`` Ding 2024 eq 15 as
    printed (its equation: :class:`~magexp.estimators.initialisers.CircleMap`), ``usual`` the standard map
    ``mod(z + 0.2 - 0.5/(2π) sin(2π z), 1)``.
    """
    if form not in FORMS:
        raise MagexpError(f"circle map form={form!r} is not allowed: choose printed or usual")
    return FORMS[form](z)
