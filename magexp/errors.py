"""The one exception type a user should ever see, as one line, and the one path (:func:`guarded`) that
turns any error into that line and an exit code, for every command."""

import os
import signal
import sys

#: the largest magnitude a reading, noise amplitude or search bound may have: squares and
#: products of a few such numbers stay far from float64 overflow (1.8e308)
LARGEST = 1e15


class MagexpError(ValueError):
    """A bad configuration value or input file.

    The message is a single line that names the bad value and says what is
    allowed; the command-line entry points print it without a traceback.
    """


def check(condition: bool, message: str) -> None:
    """Raise :class:`MagexpError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise MagexpError(message)


def check_positive_int(value, name: str, minimum: int = 1) -> int:
    """Return ``value`` as an int, or fail if it is not an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int,)) and not (
        isinstance(value, float) and value.is_integer()
    ):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be an integer >= {minimum}")
    if int(value) < minimum:
        raise MagexpError(f"{name}={value!r} is not allowed: it must be an integer >= {minimum}")
    return int(value)


def check_nonnegative(value, name: str) -> float:
    """Return ``value`` as a float, or fail if it is negative, NaN or infinite."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be a finite number >= 0") from None
    if not (v >= 0.0) or v == float("inf"):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be a finite number >= 0")
    return v


def check_magnitude(value, name: str) -> float:
    """Return ``value`` as a float, or fail if it is not finite or larger than :data:`LARGEST` in magnitude."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be a finite number") from None
    if not abs(v) <= LARGEST:
        raise MagexpError(f"{name}={value!r} is not allowed: it must be a finite number of magnitude <= {LARGEST:g}")
    return v


#: the most characters of a file's content an error message shows (:func:`excerpt`): enough to find the
#: offending token, too few to print a secret (a password line, a key of an ``.env`` file)
EXCERPT = 6


def excerpt(text) -> str:
    """``text`` read from a file, quoted for an error message: at most :data:`EXCERPT` characters,
    each one not printable shown as ``?`` (a message never prints a file's content beyond a short,
    printable excerpt)."""
    text = str(text).strip()
    shown = "".join(c if c.isprintable() else "?" for c in text[:EXCERPT])
    return repr(shown + ("..." if len(text) > EXCERPT else ""))


# ---------------------------------------------------------------------------------------------
# the one error path of every command

EXIT_BAD_INPUT, EXIT_BUG, EXIT_INTERRUPTED = 2, 3, 130
INTERRUPTED = "interrupted (Ctrl-C); finished runs are cached, rerun the same command to resume"


class Terminated(KeyboardInterrupt):
    """A command stopped by a signal other than Ctrl-C (``SIGTERM``, :func:`stop_on_signals`): it ends as
    Ctrl-C does (every cleanup that undoes an interrupted command runs), with exit code ``128 + signum``."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


#: the signal :func:`_stop` received, once one has (a library that catches every exception may have swallowed it)
_STOPPED: list[int] = []


def _stopping(signum: int) -> KeyboardInterrupt:
    """The exception a signal raises: Ctrl-C's ``KeyboardInterrupt``, or :class:`Terminated` for any other."""
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


def _stop(signum, frame) -> None:
    """The handler of :func:`stop_on_signals`: broken pipes become errors from now on (the workers are
    about to be stopped: writing to them must not kill this process silently), then Ctrl-C's path."""
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    _STOPPED.append(signum)
    raise _stopping(signum)


def raise_if_stopped() -> None:
    """Raise again the stop of a signal :func:`_stop` received: for a handler of ``Exception`` around a
    library call that may turn the signal's exception into one of its own (OmegaConf's merge, seen
    swallowing a SIGTERM into a ``ConfigKeyError``), so that the command still stops."""
    if _STOPPED:
        raise _stopping(_STOPPED[0])


def stop_on_signals() -> None:
    """Make ``SIGTERM`` and ``SIGINT`` (to this process alone, or its group) end a command as Ctrl-C does:
    one line, exit 143 / 130, nothing half-written left (the command's own cleanups)."""
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stop)


def fail(message: str, code: int = EXIT_BAD_INPUT) -> None:
    """One line on stderr (``error: ...``), then exit with ``code``."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(code)


#: optional packages and the ``pip install 'magexp[<extra>]'`` that brings each (pyproject.toml)
EXTRAS = {"cma": "cmaes", "distributed": "dask", "dask": "dask", "dask_jobqueue": "cluster", "pyulog": "ulog",
          "pymavlink": "dataflash", "rosbags": "ros", "pyswarms": "bench"}


def guarded(func, *args):
    """Call ``func(*args)`` turning every error into one line on stderr and a non-zero exit.

    The one error path of every command (``magexp``, ``magexp calibrate``, ``magexp reproduce``, a
    sweep's launcher): :class:`MagexpError` and ``OSError`` (a file or folder the user named) exit
    :data:`EXIT_BAD_INPUT`, and so does a missing optional package (the line names its extra,
    :data:`EXTRAS`); Ctrl-C exits :data:`EXIT_INTERRUPTED` with one line; anything else is a
    bug: one line and :data:`EXIT_BUG` (``MAGEXP_DEBUG=1`` shows the traceback). An error raised after a
    stop signal was received is that stop (:func:`raise_if_stopped`): the signal decides how it ends."""
    try:
        try:
            return func(*args)
        except Exception:
            raise_if_stopped()
            raise
    except MagexpError as exc:
        fail(str(exc).splitlines()[0] if str(exc) else "bad input")
    except Terminated as exc:
        fail(INTERRUPTED.replace("(Ctrl-C)", f"({signal.Signals(exc.signum).name})"), 128 + exc.signum)
    except KeyboardInterrupt:
        fail(INTERRUPTED, EXIT_INTERRUPTED)
    except OSError as exc:
        fail(f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": "))
    except SystemExit:
        raise
    except ModuleNotFoundError as exc:  # an optional package: name its extra; any other missing module is a bug
        root = (exc.name or "").split(".")[0]
        if root not in EXTRAS:
            _bug(exc)
        fail(f"this needs the optional package {root!r}, not installed: pip install 'magexp[{EXTRAS[root]}]'")
    except Exception as exc:
        _bug(exc)


def _bug(exc: BaseException) -> None:
    """A bug: one line and :data:`EXIT_BUG` (``MAGEXP_DEBUG=1``: the traceback)."""
    if os.environ.get("MAGEXP_DEBUG"):
        raise exc
    first = str(exc).splitlines()[0] if str(exc) else ""
    fail(f"unexpected {type(exc).__name__}: {first} (rerun with MAGEXP_DEBUG=1 for details)", EXIT_BUG)


def exit_code(func, *args) -> int:
    """:func:`guarded` ``func(*args)``, returning its exit code (0 when it returns) instead of exiting: the
    ``main(argv) -> int`` of a command that a caller (a test, a script) runs in its own process."""
    try:
        guarded(func, *args)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return 0
