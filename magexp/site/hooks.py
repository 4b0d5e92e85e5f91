"""The mkdocs hook (``mkdocs.yml`` ``hooks:``) that adds the results website to ``make docs``: the pages of
:mod:`magexp.site.pages` and the results' figures and CSVs join the build's files (nothing is written
into ``docs/`` or ``results/``), their entries the nav, the explorer's script and style the theme."""

from __future__ import annotations

import logging
from pathlib import Path

from mkdocs.structure.files import File, Files

from magexp.paths import RESULTS
from magexp.site.pages import PREFIX, carried, nav, pages

log = logging.getLogger("mkdocs.hooks.magexp.site")
#: the explorer's script and style, shipped in the package, served at ``results/assets/``
ASSETS = Path(__file__).with_name("assets")
NAV_TITLE = "Results website"


def _ready() -> bool:
    """Whether ``results/`` holds a report to build pages from (a checkout without results builds the docs alone)."""
    ready = (RESULTS / "REPORT.md").is_file() and (RESULTS / "APPENDIX.md").is_file()
    if not ready:
        log.warning("no results pages: %s has no REPORT.md and APPENDIX.md (make reproduce writes them)", RESULTS)
    return ready


def on_config(config):
    """The results pages in the nav, the explorer's script and style on every page."""
    if _ready():
        config.nav = [*config.nav, {NAV_TITLE: nav(RESULTS)}]
        config.extra_css.append(f"{PREFIX}/assets/explorer.css")
        config.extra_javascript.append(f"{PREFIX}/assets/explorer.js")
    return config


def on_files(files: Files, config) -> Files:
    """The generated pages, the explorer's assets and the results' figures and CSVs, added to the build."""
    if not _ready():
        return files
    for path, text in pages(RESULTS).items():
        files.append(File.generated(config, f"{PREFIX}/{path}", content=text))
    for asset in sorted(ASSETS.iterdir()):
        files.append(File.generated(config, f"{PREFIX}/assets/{asset.name}", abs_src_path=str(asset)))
    for rel in carried(RESULTS):
        files.append(File(f"{PREFIX}/{rel.as_posix()}", src_dir=str(RESULTS.parent), dest_dir=config.site_dir,
                          use_directory_urls=config.use_directory_urls))
    return files


def on_post_build(config) -> None:
    """``search/search_index.js``: the search index as a script, which the theme loads in place of the JSON
    when the site is opened from ``file://`` (as Material's offline plugin writes it, without its
    use_directory_urls change and its polyfill fetched from a CDN)."""
    index = Path(config.site_dir) / "search" / "search_index.json"
    if index.is_file():
        index.with_suffix(".js").write_text(f"var __index = {index.read_text(encoding='utf-8')}", encoding="utf-8")
