"""What a calibration is: :class:`Calibration`, the fitted ``B = W (reading - offset)`` with how good it is
(what :func:`magexp.calibrate` returns, what ``calibration.json`` holds), with the reference total field it
was fitted to (:class:`magexp.calibration.inputs.Reference`). Made by the pipeline (:mod:`magexp.calibration.fit`); written and
read back by :mod:`magexp.calibration.write`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from magexp.calibration.box import CalibrationBox
from magexp.calibration.export import export
from magexp.calibration.inputs import Reference, readings_array
from magexp.calibration.write import figure, read_parameters, save_parameters, summary, table
from magexp.core.recording import Recording
from magexp.errors import MagexpError
from magexp.estimators.result import FitResult
from magexp.scenarios.search import SearchBox


@dataclass
class Calibration:
    """A fitted calibration ``B = W (reading - offset)`` of a recording, and how good it is.

    ``w`` is in the canonical form of :data:`~magexp.calibration.quality.FORMS` (``report["w_form"]``); ``metrics`` holds the
    spreads before, after and held out; ``report`` the standard errors, conditioning, the
    undetermined combinations, the direction coverage (:mod:`magexp.core.identifiability`), the
    acceptance gate's outcome and the model selection. A calibration read back by :meth:`load`
    has no recording (``recording`` None): it applies, exports and summarises, but has no
    readings to plot.

    Made by :func:`magexp.calibrate` (or read back by :meth:`load`), not by hand.

    Attributes
    ----------
    recording : Recording or None
        The readings calibrated (None for a loaded calibration).
    estimator, objective : str
        The estimator's name and the objective fitted (``scalar``, ``vector`` or ``gyro``).
    w, offset : numpy.ndarray
        ``W`` (3 × 3, canonical form) and ``o`` (3,) of ``B = W (r - o)``: ``o`` in the raw unit.
    reference : Reference
        The reference total field fitted to (:class:`magexp.calibration.inputs.Reference`).
    search : CalibrationBox, SearchBox or None
        The search box of the fit (None: loaded).
    fit : FitResult or None
        The estimator's result (None: loaded).
    calibrated : numpy.ndarray
        ``(N, 3)`` calibrated readings, in :attr:`field_unit`.
    metrics, report : dict
        The spreads before, after and held out; the quality report (standard errors, conditioning, gate, model).
    seed : int
        The seed the estimator's generator derived from.
    config : dict
        The settings it was made with.
    saved : dict or None
        The JSON it was loaded from.
    heldout_fits : list
        Each held-out fold's ``(W_k, o_k)``.
    """

    recording: Recording | None
    estimator: str
    objective: str
    w: np.ndarray
    offset: np.ndarray
    reference: Reference
    search: CalibrationBox | SearchBox | None
    fit: FitResult | None
    calibrated: np.ndarray
    metrics: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)
    seed: int = 0
    config: dict = field(default_factory=dict)  # the settings it was made with (the command's config, the call's)
    saved: dict | None = None  # the JSON it was loaded from (:meth:`load`)
    heldout_fits: list = field(default_factory=list)  # each held-out fold's (W_k, o_k) (magexp.calibration.heading)

    @property
    def unit(self) -> str:
        """Unit of the raw readings."""
        return self.recording.unit if self.recording is not None else self.saved["unit"]

    @property
    def field_unit(self) -> str:
        """Unit of the calibrated field (the recording's, or the field model's nT for raw counts)."""
        return self.reference.unit or self.unit

    @property
    def name(self) -> str:
        """The recording's file name (a loaded calibration's: the one it was made from)."""
        return self.recording.name if self.recording is not None else Path(self.saved["recording"]).name

    @property
    def model(self) -> str:
        """The model fitted (``report['model']``: ``sphere``, ``diagonal``, ``full`` or ``gyro``)."""
        return self.report.get("model", "full")

    def apply(self, readings) -> np.ndarray:
        """``B = W (r - o)`` of raw ``readings`` (``(N, 3)`` or ``(3,)``, the recording's unit).

        .. math:: \\mathbf B_i = W (\\mathbf r_i - \\mathbf o)

        the calibration of every problem (:mod:`magexp.problems`; Yuan 2018's ``W = S^{-1}``, ``o = b``), whose
        total-field RMS against the reference is Ding 2024's eq 18.

        Parameters
        ----------
        readings : array_like
            ``(N, 3)`` or ``(3,)`` raw readings, the recording's unit.

        Returns
        -------
        numpy.ndarray
            The calibrated field ``B``, shape of ``readings``, in :attr:`field_unit`.

        Raises
        ------
        MagexpError
            Readings of another shape or type, or not finite (the first such row named).
        """
        r = readings_array(readings)
        if r.shape[-1:] != (3,) or r.ndim > 2:
            raise MagexpError(f"readings of shape {r.shape} are not allowed: give (N, 3) or (3,) raw readings")
        bad = np.flatnonzero(~np.isfinite(r.reshape(-1, 3)).all(axis=1))
        if bad.size:
            raise MagexpError(f"readings row {bad[0]} = {r.reshape(-1, 3)[bad[0]].tolist()} is not allowed: every "
                              f"reading must be finite ({bad.size} rows hold NaN or infinity)")
        return (r - self.offset) @ self.w.T

    def save(self, path, *, overwrite: bool = False) -> Path:
        """Write ``calibration.json`` content (versioned, with provenance) to ``path``; an existing
        file is refused in one line unless ``overwrite``, and then replaced only if a calibration wrote it,
        never the recording. :meth:`load` reads it back exactly.

        Parameters
        ----------
        path : str or Path
            The file to write (conventionally ``calibration.json``).
        overwrite : bool
            Replace an existing file a calibration wrote (never the recording, never another file).

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        MagexpError
            An existing file without ``overwrite``, or one no calibration wrote.
        """
        return save_parameters(self, path, overwrite=overwrite)

    @classmethod
    def load(cls, path) -> "Calibration":
        """A :class:`Calibration` from a ``calibration.json`` (:meth:`save`, ``magexp calibrate``).

        Parameters
        ----------
        path : str or Path
            A ``calibration.json`` (formats :data:`magexp.calibration.schema.FORMATS`), checked key by key
            (:func:`magexp.calibration.write.read_parameters`) before anything is built from it.

        Returns
        -------
        Calibration
            The calibration, without its recording.

        Raises
        ------
        MagexpError
            A file that is not a readable calibration.
        """
        data = read_parameters(path)
        ref = data["reference"]
        reference = Reference(np.array([ref["total"]]), ref["source"], ref["estimated"], ref.get("unit"),
                              ref.get("field_model"))
        quality = data.get("quality", {})
        cal = cls(recording=None, estimator=data["estimator"], objective=data["objective"],
                  w=np.array(data["W"], float), offset=np.array(data["offset"], float), reference=reference,
                  search=None, fit=None, calibrated=np.zeros((0, 3)), metrics=data.get("metrics", {}),
                  report=quality, seed=data.get("seed", 0), config=data.get("config", {}), saved=data)
        try:  # the records the summary reads beyond the schema's keys (the heading's, the gate's)
            summary(cal)
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
            raise MagexpError(f"{Path(path).name}: its quality or metrics record is not one a calibration writes "
                              f"({type(exc).__name__} {str(exc)[:60]}): give a file written by magexp calibrate or "
                              "Calibration.save") from None
        return cal

    def __repr__(self) -> str:
        m = self.metrics
        held = (f", held out {100 * m['heldout_spread']:.3g} %" if "heldout_spread" in m
                else ", held out not measured" if m.get("heldout_design") == "none" else "")
        gate = self.report.get("gate") or {}
        state = "" if not gate else (", gate passed" if gate.get("passed") else ", gate FAILED (accepted)")
        return (f"<Calibration {self.name}: {self.model} model by {self.estimator}, spread "
                f"{100 * m.get('spread_before', float('nan')):.3g} % -> {100 * m.get('spread_after', float('nan')):.3g} %"
                f"{held}{state}; B = W (r - o), r in {self.unit}, B in {self.field_unit}>")

    def summary(self) -> str:
        """The printed summary of ``magexp calibrate`` (the key numbers, one per line).

        Returns
        -------
        str
            ``key  value`` lines.
        """
        return table(summary(self))

    def plot(self):
        """The before/after figure (:mod:`magexp.calibration.figure`); returns the matplotlib Figure.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.

        Raises
        ------
        MagexpError
            A loaded calibration (no readings).
        """
        if self.recording is None:
            raise MagexpError("plot() is not allowed for a loaded calibration: it has no readings; calibrate the "
                              "recording again, or plot cal.apply(readings) yourself")
        return figure(self)

    def export(self, target: str, path=None, *, overwrite: bool = False, **options) -> Path:
        """Write ``target``'s file (``ardupilot``, ``px4``, ``ros``, ``c``: :mod:`magexp.calibration.export`); an
        existing file is refused in one line unless ``overwrite``, and then replaced only if a calibration
        wrote it (:func:`magexp.calibration.folder.is_calibrations`), never the recording.

        Parameters
        ----------
        target : str
            ``ardupilot``, ``px4``, ``ros`` or ``c``.
        path : str, Path or None
            The folder or file (None: the working folder).
        overwrite : bool
            As in :meth:`save`.
        **options
            The target's options (:func:`magexp.calibration.export.options_of` lists them): ``instance``, the
            compass or slot (``ardupilot`` 0-2, ``px4`` 0-3); ``counts_nt``, nT per count of a raw-count
            recording; ``max_rotation_deg``, the largest rotation of ``W = R S`` a symmetric-only target
            (ArduPilot, PX4) may leave out; ``orient``, write ``W``'s determined rotation as the board
            orientation; ``rotation``, PX4's ``R`` taken out of ``W`` first; ``node``, ``namespace`` (``ros``);
            ``name``, the C identifier (``c``); ``notes``, comment lines at the file's head.

        Returns
        -------
        Path
            The firmware's file, written atomically.

        Raises
        ------
        MagexpError
            An export the target refuses (:func:`magexp.calibration.export.render`), in one line.
        """
        return export(self, target, path, overwrite=overwrite, **options)

