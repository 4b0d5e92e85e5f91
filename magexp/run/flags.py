"""The options of magexp's commands: the flags of ``magexp`` that Hydra would read (:func:`check_flags`),
and the ``argparse`` parser of the other commands, whose errors are one line (:class:`OneLineParser`).

Every refusal is one line that names the option, its value and what is allowed, and exits 2.
"""

from __future__ import annotations

import argparse
import sys

from magexp.errors import MagexpError


#: what ``--cfg`` may show (Hydra's choices)
CFG_CHOICES = ("job", "hydra", "all")


def check_flags(flags: dict) -> None:
    """The options of ``magexp`` that Hydra would read, checked before Hydra sees them (whose own
    errors are its usage text, or exit 1): ``--cfg job|hydra|all``, ``--config-name`` naming a
    primary config of ``conf/``; ``--experimental-rerun`` (which unpickles a file) and ``--config-dir`` /
    ``--config-path`` (configs from elsewhere, with their own ``_target_``) are refused."""

    for flag in ("--cfg", "-c"):
        if flag in flags and flags[flag] not in CFG_CHOICES:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed: choose one of {', '.join(CFG_CHOICES)}")
    names = ["config"]  # calibrate.yaml is magexp calibrate's own (magexp calibrate KEY=VALUE ...)
    for flag in ("--config-name", "-cn"):
        if flag in flags and flags[flag] not in names:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed: choose one of {', '.join(names)}")
    if "--experimental-rerun" in flags:
        raise MagexpError(f"--experimental-rerun {flags['--experimental-rerun']!r} is not allowed: it unpickles a "
                          "file, which can run any code; rerun with the overrides of the run's config.yaml")
    for flag in ("--config-dir", "-cd", "--config-path", "-cp"):
        if flag in flags:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed: configs come from magexp's conf/ only (a "
                              "folder of configs would name its own code); add a config there (docs/extending.md)")


class OneLineParser(argparse.ArgumentParser):
    """``argparse`` whose every error is one line on stderr and exit 2 (``--help`` still prints the usage)."""

    def error(self, message: str):
        """Print ``message``'s first line (not the usage text) and exit with code 2."""
        print(f"error: {message.splitlines()[0]} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(2)
