"""The live stream of ``magexp calibrate``: where its bytes come from (a serial port, :class:`SerialSource`, or
standard input, :class:`StdinSource`), how they are cut into lines (:class:`LineCutter`, every line at most
``live.max_line`` bytes) and how each line is judged and kept (:class:`StreamFile`).

The stream is one of the text formats :mod:`magexp.core.recordings` reads (told by
:func:`magexp.core.readers.detect` from its first line, as a file's is): headerless ``x y z`` lines
(``plain``), a header row (``header-row``), ``Fs,``/``mx,my,mz`` lines (``header-counts``), named columns or
``magexp-recording v1``. The header lines (every line before the first data row: the metadata, then the row
that names the columns) are kept as they came; a data row is kept when it holds as many cells as the header
names (3 for ``plain``), each a finite number (:func:`magexp.core.textfiles.numeric_table`, the readers' own
parsing); any other line is *garbage*, counted and named once, never kept. What is kept is written to the
stream file (``stream.txt``) as it arrives, line for line as received, so that the file the live check reads
(:mod:`magexp.calibration.live`) and the one ``magexp calibrate data.path=`` reads back are the same.
"""

from __future__ import annotations

import os
import select
import sys
from pathlib import Path

from magexp.core.readers import detect
from magexp.core.textfiles import numeric_table
from magexp.core.readers.header_row import header_cells, header_columns
from magexp.core.readers.magexp_v1 import VERSION_LINE
from magexp.core.readers.named_columns import NAMED
from magexp.core.readers.plain import split
from magexp.errors import MagexpError, excerpt

#: bytes read from a source at most at a time
CHUNK = 1 << 16
#: seconds a serial port's read waits for data at most
POLL = 0.1


class StdinSource:
    """Standard input (``data.path=-``) read without blocking longer than a timeout (``select``)."""

    name = "standard input"

    def __init__(self, fd: int = 0):
        self.fd = fd

    def read(self, timeout: float) -> bytes | None:
        """The bytes available within ``timeout`` seconds (``b""``: none yet), None at the end of the stream."""
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if not ready:
            return b""
        try:
            data = os.read(self.fd, CHUNK)
        except OSError:  # a terminal whose other side went away
            return None
        return data or None

    def close(self) -> None:
        """Nothing to close: standard input belongs to the caller."""


class SerialSource:
    """A serial port read with pyserial (``data.serial``, ``data.baud``): a USB-serial adapter, a board's
    CDC port, or a pseudo-terminal."""

    def __init__(self, port: str, baud: int):
        try:
            import serial  # an optional package (magexp[serial]): imported when a port is read
        except ModuleNotFoundError:
            raise MagexpError(f"data.serial={port!r} needs the optional package pyserial, not installed: "
                              "pip install 'magexp[serial]'") from None
        self._errors = (serial.SerialException, OSError)
        try:
            self.port = serial.Serial(port, baudrate=baud, timeout=POLL)
        except self._errors as exc:
            raise MagexpError(f"data.serial={port!r} cannot be opened ({str(exc).splitlines()[0]}): give the "
                              "device path of the port (e.g. /dev/ttyUSB0, COM3)") from None
        self.name = f"{port} at {baud} baud"

    def read(self, timeout: float) -> bytes | None:
        """As :meth:`StdinSource.read`, waiting :data:`POLL` seconds at most (the port's own timeout, set once:
        ``timeout`` is not used); a port that went away (unplugged) ends the stream."""
        try:
            return self.port.read(max(1, min(self.port.in_waiting, CHUNK)))
        except self._errors:  # the device reports readiness but gives nothing: disconnected
            return None

    def close(self) -> None:
        """Close the port."""
        self.port.close()


def open_source(data) -> StdinSource | SerialSource:
    """The source ``data.*`` names: ``data.serial`` (with ``data.baud``), else standard input (``data.path=-``)."""
    if data.get("serial") is None:
        return StdinSource(sys.stdin.fileno())
    return SerialSource(str(data.serial), int(data.baud))


class LineCutter:
    """Bytes into complete lines, none longer than ``max_line`` bytes (a longer one is cut off at its end
    and returned as ``None``: garbage, whatever followed it on that line dropped)."""

    def __init__(self, max_line: int):
        self.max_line, self.tail, self.skipping = max_line, b"", False

    def feed(self, data: bytes) -> list[bytes | None]:
        """The complete lines of ``data`` after what came before (their end-of-line removed); None for a line
        over the limit."""
        parts = (self.tail + data).split(b"\n")
        self.tail = parts.pop()
        lines: list[bytes | None] = []
        for part in parts:
            lines.append(None if self.skipping or len(part) > self.max_line else part.rstrip(b"\r"))
            self.skipping = False
        if len(self.tail) > self.max_line:
            if not self.skipping:
                lines.append(None)
            self.tail, self.skipping = b"", True
        return lines

    def flush(self) -> list[bytes | None]:
        """The last line when the stream ends without an end-of-line."""
        tail, self.tail = self.tail, b""
        return [] if self.skipping or not tail.strip() else [tail.rstrip(b"\r")]


class StreamFile:
    """The stream's lines judged and kept (module docstring): the header lines, then the data rows, written to
    ``path`` as they arrive; the garbage counted, the first one named."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.fh = open(self.path, "w", encoding="utf-8", newline="\n")  # noqa: SIM115 (closed by close())
        self.format: str | None = None
        self.header: list[str] = []
        self.ncols = 0
        self.rows = 0
        self.lines = 0
        self.garbage = 0
        self.first_garbage: str | None = None

    def add(self, lines: list[bytes | None]) -> int:
        """Judge ``lines`` and keep the good ones (written and flushed); return how many data rows were kept."""
        rows = []
        for raw in lines:
            self.lines += 1
            text = self._text(raw)
            if text is None or not text.strip():
                continue
            if self.ncols == 0 and not self._header_line(text):
                continue
            rows.append((self.lines, text))
        kept = self._rows(rows)
        self.fh.write("".join(f"{text}\n" for text in kept))
        self.fh.flush()
        self.rows += len(kept)
        return len(kept)

    def _text(self, raw: bytes | None) -> str | None:
        """``raw`` as text, or None (counted as garbage) when over the limit, not UTF-8 or holding a NUL."""
        try:
            text = None if raw is None or b"\x00" in raw else raw.decode("utf-8-sig" if self.lines == 1 else "utf-8")
        except UnicodeDecodeError:
            text = None
        if text is None:
            self._garbage(raw.decode("utf-8", "replace") if raw is not None else "(over live.max_line bytes)")
        return text

    def _header_line(self, text: str) -> bool:
        """A line before the first data row: the format told from the first one (a line no format starts with
        is garbage: a board's greeting), the header kept; True when it is a data row (a headerless stream's first)."""
        if self.format is None:
            self.fh.write(text + "\n")
            self.fh.flush()
            self.format = detect(self.path)
            self.fh.seek(0)
            self.fh.truncate()
            if self.format == "magexp-v1" and text.strip() != VERSION_LINE:
                self.format = None
                self._garbage(text)
                return False
            if self.format == "plain":
                self.ncols = 3
                return True
        elif self.format == "magexp-v1" and not text.lstrip().startswith("#") and header_columns(text) is None:
            self._garbage(text)
            return False
        self.header.append(text)
        self.fh.write(text + "\n")
        if self._names_columns(text):
            self.ncols = len(header_cells(text))
        return False

    def _names_columns(self, text: str) -> bool:
        """Whether ``text`` is the row naming the columns (the last header line) of the stream's format."""
        if self.format == "named-columns":
            return any(NAMED.match(cell) for cell in text.split(","))
        if self.format == "magexp-v1" and text.lstrip().startswith("#"):
            return False
        return header_columns(text) is not None

    def _rows(self, rows: list[tuple[int, str]]) -> list[str]:
        """The rows of ``rows`` (line number, text) that hold ``ncols`` finite numbers: all at once by the
        readers' own table parser when every row does, else one by one (the others counted as garbage)."""
        if not rows:
            return []
        cells = [",".join(split(text) if self.format == "plain" else header_cells(text)) for _, text in rows]
        try:
            numeric_table(cells, str(self.path.name), rows[0][0], self.ncols)
            return [text for _, text in rows]
        except MagexpError:
            pass
        kept = []
        for (k, text), row in zip(rows, cells):
            try:
                numeric_table([row], str(self.path.name), k, self.ncols)
                kept.append(text)
            except MagexpError:
                self._garbage(text, k)
        return kept

    def _garbage(self, text: str, line: int | None = None) -> None:
        """Count a garbage line; remember the first."""
        self.garbage += 1
        if self.first_garbage is None:
            self.first_garbage = f"line {line or self.lines} {excerpt(text)}"

    def garbage_line(self) -> str | None:
        """The one line about the garbage (None: there was none)."""
        if not self.garbage:
            return None
        what = "3 numbers x y z" if self.format == "plain" else f"{self.ncols} numbers, as the header names"
        return (f"{self.garbage} garbage line{'s' if self.garbage > 1 else ''} of {self.lines} skipped and not kept "
                f"(first: {self.first_garbage}): a data line must hold {what}")

    def close(self) -> None:
        """Close the stream file (what was kept stays)."""
        self.fh.close()
