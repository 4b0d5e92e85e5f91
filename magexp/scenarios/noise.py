"""Reading-noise models shared by the simulated scenarios."""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError, check_magnitude, check_nonnegative

KINDS = ("uniform", "gaussian")


class Noise:
    """Additive per-axis reading noise.

    ``kind="uniform"``: ``amplitude * (U(0,1) - 0.5)``, i.e. uniform on
    ``[-A/2, A/2]`` (Ding 2024's "random noise of maximum amplitude A"; the
    convention that reproduces its RMS values), standard deviation ``A/sqrt(12)``.
    ``kind="gaussian"``: zero-mean normal with standard deviation ``amplitude``. ``amplitude`` (``A`` >= 0)
    is in the readings' unit; ``name`` is the config key a refusal names.
    """

    def __init__(self, amplitude: float, kind: str = "uniform", name: str = "scenario.noise"):
        self.amplitude = check_magnitude(check_nonnegative(amplitude, name), name)
        if kind not in KINDS:
            raise MagexpError(f"{name}_kind={kind!r} is not allowed: choose one of {', '.join(KINDS)}")
        self.kind = kind

    @property
    def std(self) -> float:
        """The per-axis standard deviation: ``A/√12`` for uniform noise of amplitude ``A``."""
        return self.amplitude / np.sqrt(12.0) if self.kind == "uniform" else self.amplitude

    def sample(self, shape, *, rng: np.random.Generator) -> np.ndarray:
        """Draw the noise of ``shape`` readings' axes."""
        if self.kind == "uniform":
            return self.amplitude * (rng.random(shape) - 0.5)
        return self.amplitude * rng.standard_normal(shape)
