"""``python -m magexp.core.readers``: rewrite the table of formats in docs/calibrate.md from the format modules."""

from magexp.core.generated import with_section
from magexp.core.readers import BEGIN, END, docs_section
from magexp.paths import ROOT

if __name__ == "__main__":
    page = ROOT / "docs" / "calibrate.md"
    page.write_text(with_section(page.read_text(), BEGIN, END, docs_section()))
