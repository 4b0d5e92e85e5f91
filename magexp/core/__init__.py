"""The model's foundations: data structures, geometry, reference fields, seeding, metrics, bounds and
the readers of recorded data.

Lives here: :mod:`~magexp.core.dataset` (the ``Dataset`` every scenario produces),
:mod:`~magexp.core.geometry` (rotations, attitudes), :mod:`~magexp.core.igrf` (reference field),
:mod:`~magexp.core.seeding` (every random draw from the run's seed), :mod:`~magexp.core.metrics` (and the
one total-field RMS), :mod:`~magexp.core.outcomes` (what a successful run is, a failed majority, a face of
the search box, the round-off floor),
:mod:`~magexp.core.bounds` (Cramér-Rao bounds), :mod:`~magexp.core.identifiability` (canonical form,
standard errors, coverage, spread), :mod:`~magexp.core.ellipsoid` (the algebraic ellipsoid fit),
:mod:`~magexp.core.recording` (a recording and its Dataset), :mod:`~magexp.core.readers` (one module per
recording format: its name, detection and reader), :mod:`~magexp.core.recordings` (the loader),
:mod:`~magexp.core.datafiles`,
:mod:`~magexp.core.atomic` (atomic file writes).

May import: numpy, scipy, omegaconf (a scenario's config node, :mod:`~magexp.core.seeding`), pandas and
ppigrf (lazily, measured), :mod:`magexp.errors`, :mod:`magexp.paths` and other ``core`` modules only.
"""
