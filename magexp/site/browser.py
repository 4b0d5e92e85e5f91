"""The results website built and opened in headless Chromium: the build ``make docs`` runs, the system's
Chromium driven by Playwright (no browser download), used by ``python -m magexp.site --screenshot`` and
by ``tests/test_site.py``."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from magexp.errors import MagexpError
from magexp.paths import ROOT

#: where Debian's package puts Chromium (apt-get install chromium); MAGEXP_CHROMIUM overrides it
CHROMIUM = "/usr/bin/chromium"
#: Chromium's switches: headless, and nothing fetched from the network behind the page's back
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
#: the build's time limit (make docs takes well under a minute on two cores)
BUILD_SECONDS = 300
#: the explorer's page in the build
EXPLORER = "results/explorer/index.html"


def chromium() -> str:
    """The Chromium executable to drive, or a :class:`MagexpError` saying how to get one."""
    path = os.environ.get("MAGEXP_CHROMIUM") or shutil.which("chromium") or CHROMIUM
    if not Path(path).is_file():
        raise MagexpError(f"no Chromium at {path!r}: install Debian's package (apt-get install chromium) "
                          "or set MAGEXP_CHROMIUM to its executable")
    return path


def build(site: Path) -> None:
    """The documentation site with its results pages, built strictly into ``site`` as ``make docs`` does."""
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)], cwd=ROOT,
                          capture_output=True, text=True, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
                          timeout=BUILD_SECONDS)
    if done.returncode:
        raise MagexpError(f"mkdocs build failed: {done.stderr.strip().splitlines()[-1:]}")


def launch(playwright):
    """Headless Chromium (:func:`chromium`, :data:`ARGS`) under a started ``playwright``."""
    return playwright.chromium.launch(executable_path=chromium(), args=ARGS, headless=True)


def playwright():
    """Playwright's synchronous entry point, or a :class:`MagexpError` naming the package to install."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise MagexpError("the Python package 'playwright' is not installed: pip install -e '.[test]' "
                          "(it drives the system's Chromium; no browser is downloaded)") from None
    return sync_playwright()


def require() -> None:
    """Nothing, when Playwright and a Chromium are there to take a screenshot; else the
    :class:`MagexpError` saying which is missing (before anything is built or written)."""
    playwright()
    chromium()


def explorer_screenshot(site: Path, out: Path, paper: str = "yuan2018") -> None:
    """A screenshot of the claims explorer in ``site`` into ``out``: the claims of ``paper``, sorted by
    p, the first row opened to its evidence and figure."""
    with playwright() as pw:
        browser = launch(pw)
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.goto((site / EXPLORER).as_uri())
        claims = page.locator('.mx-explorer[data-table="claims"]')
        claims.locator('select[data-filter="paper"]').select_option(paper)
        claims.locator('th[data-sort="p"]').click()
        claims.locator("tr.mx-row").first.click()
        page.locator(".mx-detail img").first.evaluate("img => img.decode()")
        page.locator("h2#claims").scroll_into_view_if_needed()
        out.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(out))
        browser.close()
