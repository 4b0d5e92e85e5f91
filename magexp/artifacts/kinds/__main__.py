"""``python -m magexp.artifacts.kinds``: rewrite the table of kinds in docs/extending.md from the kind modules."""

from magexp.artifacts.kinds import with_docs_section
from magexp.paths import ROOT

if __name__ == "__main__":
    page = ROOT / "docs" / "extending.md"
    page.write_text(with_docs_section(page.read_text()))
