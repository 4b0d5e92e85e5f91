"""magexp's one entry point: ``magexp`` (or ``python -m magexp``), one error path.

==============================  ==================================================================
``magexp [KEY=VALUE ...]``      one run, ``-m`` a sweep, ``--cfg job``, ``--help``, ``--version``
                                (:mod:`magexp.run.command`)
``magexp calibrate KEY=...``    calibrate a recording (:mod:`magexp.calibration.command`)
``magexp reproduce PAPER ...``  regenerate a paper's figures, tables and the report
                                (:mod:`magexp.artifacts.reproduce`; what ``make reproduce`` runs)
``magexp verify [OPTIONS]``     compare a reproduction with the committed results
                                (:mod:`magexp.artifacts.verify`; what ``make verify`` runs)
``magexp new-paper NAME``       a new paper's folder ``experiments/NAME/`` that reproduces as written
                                (:mod:`magexp.artifacts.scaffold`)
==============================  ==================================================================

Every command runs under :func:`magexp.errors.guarded`: any error is one line on stderr and an
exit code (2 bad input, 3 a bug, 130 Ctrl-C, 143 SIGTERM).
"""

from __future__ import annotations

import signal
import sys

from magexp import paths
from magexp.core.limits import check_limits
from magexp.errors import guarded, stop_on_signals
from magexp.run.folders import check_cache_folder
from magexp.run.threads import one_blas_thread


def command(name: str):
    """The ``main(argv)`` of subcommand ``name`` (``run`` for anything else). Each is imported when it
    is called: a single run does not import the reproduction's pandas and matplotlib or the
    calibration's readers (measured: ``python -m magexp --help`` 0.6 s instead of 1.4 s)."""
    if name == "calibrate":
        from magexp.calibration.command import command as main
    elif name == "reproduce":
        from magexp.artifacts.reproduce import command as main
    elif name == "verify":
        from magexp.artifacts.verify import command as main
    elif name == "new-paper":
        from magexp.artifacts.scaffold import command as main
    else:
        from magexp.run.command import run_command as main
    return main


def main(argv: list[str] | None = None) -> None:
    """Entry point of ``magexp`` / ``python -m magexp``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if argv is None:  # a closed pipe (magexp --help | head) ends quietly, as for any Unix tool
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        stop_on_signals()  # SIGTERM, and SIGINT to this process alone, end as Ctrl-C does
    name = args[0] if args and args[0] in ("calibrate", "reproduce", "verify", "new-paper") else "run"
    one_blas_thread()  # this process and its workers; before the command imports numpy
    guarded(start, name, args[1:] if name != "run" else args)


def start(name: str, args: list[str]) -> None:
    """Subcommand ``name`` on ``args``, once the limits' variables are numbers and the run cache's folder is
    allowed (not inside ``results/``)."""
    check_limits()  # every MAGEXP_MAX_* a number > 0, whether or not this command consults it
    check_cache_folder(str(paths.CACHE))
    command(name)(args)


if __name__ == "__main__":
    main()
