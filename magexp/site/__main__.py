"""``python -m magexp.site``: build the documentation site with its results pages (as ``make docs``) into
``--site-dir``; with ``--screenshot PNG``, also photograph the claims explorer in headless Chromium (the
README's picture: ``python -m magexp.site --screenshot docs/img/explorer.png``). Bad input or a missing
Chromium: one line, exit code 2."""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from magexp.errors import MagexpError
from magexp.site.browser import build, explorer_screenshot, require


def main(argv: list[str] | None = None) -> None:
    """Build the site (and the explorer's screenshot) as the options ask; exit code 2 on bad input."""
    parser = argparse.ArgumentParser(prog="python -m magexp.site", description=__doc__.split("\n\n")[0])
    parser.add_argument("--site-dir", type=Path, default=None,
                        help="where to build the site (default: a temporary folder, removed after)")
    parser.add_argument("--screenshot", type=Path, default=None, metavar="PNG",
                        help="write a screenshot of the claims explorer to this PNG")
    args = parser.parse_args(argv)
    if args.screenshot is not None and args.screenshot.suffix.lower() != ".png":
        parser.exit(2, f"--screenshot {str(args.screenshot)!r}: a .png file is allowed\n")
    try:
        if args.screenshot is not None:
            require()
        with tempfile.TemporaryDirectory(prefix="magexp-site-") as tmp:
            site = args.site_dir or Path(tmp) / "site"
            build(site)
            if args.screenshot is not None:
                explorer_screenshot(site, args.screenshot)
    except MagexpError as exc:
        parser.exit(2, f"{exc}\n")
    where = site if args.site_dir else "a temporary folder (removed)"
    print(f"site built strictly into {where}" + (f"; explorer screenshot: {args.screenshot}" if args.screenshot else ""))


if __name__ == "__main__":
    main(sys.argv[1:])
