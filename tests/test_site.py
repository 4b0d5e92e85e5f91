"""The results website in a real browser (issue 43 item 4): the site built as ``make docs`` builds it, every
page opened in headless Chromium (Debian's package, installed here where missing and possible; else the
test is skipped with one line), no broken link or image, no console error, the explorer's filters and
sorting at work, and each paper page's first screen not blank (its screenshot kept under the test's tmp
folder, ``screenshots/``). make test-full only: it builds the site and drives a browser."""

from __future__ import annotations

import csv
import functools
import http.server
import os
import shutil
import subprocess
import threading
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from magexp.errors import MagexpError
from magexp.paths import RESULTS
from magexp.site.browser import EXPLORER, build, chromium, launch, playwright
from magexp.site.data import explorer_data

pytestmark = pytest.mark.full
#: a screenshot of a page's first screen has at least this many distinct colours and this share of
#: pixels that are not the background (text, tables, a figure): a blank or unstyled page has fewer
MIN_COLOURS, MIN_INK = 64, 0.02
#: apt-get's time limit when the setup installs Chromium
INSTALL_SECONDS = 600


def _ensure_chromium() -> str:
    """The Chromium to drive: the system's, installed with apt-get when missing and this process is root."""
    try:
        return chromium()
    except MagexpError as missing:
        if not (shutil.which("apt-get") and hasattr(os, "geteuid") and os.geteuid() == 0):
            pytest.skip(f"{missing} (and apt-get as root is not available to install it)")
        done = subprocess.run(["apt-get", "install", "-y", "--no-install-recommends", "chromium"],
                              capture_output=True, text=True, timeout=INSTALL_SECONDS)
        if done.returncode:
            pytest.skip(f"apt-get install chromium failed: {done.stderr.strip().splitlines()[-1:]}")
        return chromium()


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    pytest.importorskip("playwright", reason="the Python package playwright is not installed (pip install -e '.[test]')")
    if not (RESULTS / "REPORT.md").exists():
        pytest.skip("results/ holds no report to build pages from")
    _ensure_chromium()
    out = tmp_path_factory.mktemp("site") / "site"
    build(out)
    return out


@pytest.fixture(scope="module")
def browser(site):
    with playwright() as pw:
        chrome = launch(pw)
        yield chrome
        chrome.close()


def _target(url: str, site: Path) -> Path | None:
    """The file a ``file://`` address inside the site names (a folder: its index.html); None outside it."""
    parsed = urlparse(url)
    if parsed.scheme != "file":
        return None
    path = Path(unquote(parsed.path))
    if site not in path.parents and path != site:
        return None
    return path / "index.html" if path.is_dir() or not path.suffix else path


def _ink(png: Path) -> tuple[int, float]:
    """The distinct colours of a screenshot and the share of its pixels that are not its commonest colour."""
    from PIL import Image

    image = Image.open(png).convert("RGB")
    colours = image.getcolors(maxcolors=1 << 24)
    commonest = max(count for count, _ in colours)
    return len(colours), 1 - commonest / (image.width * image.height)


def test_every_page_opens_without_a_broken_link_image_or_console_error(site, browser):
    pages = sorted(p for p in site.rglob("index.html"))
    assert any("results" in p.parts for p in pages)
    page = browser.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(f"{page.url}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"{page.url}: {e}"))
    broken = []
    for html in pages:
        page.goto(html.as_uri())
        for url in page.eval_on_selector_all("a[href]", "els => els.map(e => e.href)") + \
                page.eval_on_selector_all("img[src]", "els => els.map(e => e.src)"):
            target = _target(url.split("#")[0].split("?")[0], site)
            if target is not None and not target.exists():
                broken.append(f"{html.relative_to(site)} -> {url}")
    page.close()
    assert not broken, f"{len(broken)} broken links or images, e.g. {broken[:5]}"
    assert not errors, f"console errors: {errors[:5]}"


def test_the_explorers_filters_and_sorting_change_the_rows_shown(site, browser):
    with (RESULTS / "claims.csv").open(newline="") as fh:
        claims = list(csv.DictReader(fh))
    page = browser.new_page()
    page.goto((site / EXPLORER).as_uri())
    table = page.locator('.mx-explorer[data-table="claims"]')
    shown = table.locator("tr.mx-row")
    assert shown.count() == len(claims)
    verdict = next(v for v in ("contradicted", "does not hold") if any(c["verdict"] == v for c in claims))
    table.locator('select[data-filter="verdict"]').select_option(verdict)
    assert shown.count() == sum(c["verdict"] == verdict for c in claims) < len(claims)
    table.locator('select[data-filter="paper"]').select_option(claims[0]["paper"])
    assert shown.count() == sum(c["verdict"] == verdict and c["paper"] == claims[0]["paper"] for c in claims)
    table.locator('select[data-filter="verdict"]').select_option("")
    table.locator('select[data-filter="paper"]').select_option("")
    data = explorer_data(RESULTS)["claims"]["rows"]
    reading = next(r["reading"] for r in data if "; " in r["reading"]).split("; ")[-1]  # one of a claim's readings
    table.locator('select[data-filter="reading"]').select_option(reading)
    assert shown.count() == sum(reading in r["reading"].split("; ") for r in data) > 0
    table.locator('select[data-filter="reading"]').select_option("")
    table.locator('th[data-sort="p"]').click()
    ps = [float(t) for t in table.locator('td[data-key="p"]').all_inner_texts() if t]
    assert len(ps) > 10 and ps == sorted(ps)
    shown.first.click()
    opened = table.locator(".mx-detail")
    assert opened.count() == 1 and "evidence" in opened.inner_text()
    numbers = page.locator('.mx-explorer[data-table="numbers"]')
    every = numbers.locator("tr.mx-row").count()
    numbers.locator('select[data-filter="verdict"]').select_option("reproduced")
    assert 0 < numbers.locator("tr.mx-row").count() < every
    page.close()


def test_the_sites_search_finds_a_claim_when_served(site, browser):
    """The site's own search (served by any static server: the theme's search runs in a web worker)."""
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.goto(f"http://127.0.0.1:{server.server_port}/results/")
        page.keyboard.press("s")
        page.keyboard.type("Circle map")
        page.locator(".md-search-result__item").first.wait_for(timeout=15_000)
        assert "results/" in page.locator(".md-search-result__item a").first.get_attribute("href")
        page.close()
    finally:
        server.shutdown()


def test_each_paper_page_is_not_blank(site, browser, tmp_path_factory):
    shots = tmp_path_factory.mktemp("screenshots")
    papers = sorted(p.parent for p in (site / "results").glob("*/appendix/index.html"))
    assert papers
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    for paper in papers:
        page.goto((paper.parent / "index.html").as_uri())
        png = shots / f"{paper.parent.name}.png"
        page.screenshot(path=str(png))
        colours, ink = _ink(png)
        assert colours >= MIN_COLOURS and ink >= MIN_INK, f"{png} looks blank: {colours} colours, {ink:.1%} ink"
    page.close()
    print(f"screenshots of the paper pages: {shots}")
