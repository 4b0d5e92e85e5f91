"""The Ding 2024 artifacts run end to end at tiny sizes into a temporary folder."""

import pandas as pd
import pytest

from magexp.reproduce import reproduce_paper
from magexp.report import build
from magexp.summary import COLUMNS


@pytest.mark.slow
def test_ding2024_artifacts_tiny(tmp_path):
    summary = reproduce_paper("ding2024", root=tmp_path, seeds=2, jobs=1, tiny=True, log=lambda *_: None)
    assert list(summary.columns) == COLUMNS
    for stem in ("fig2", "fig3", "fig4", "fig5", "fig6", "table_rms"):
        assert (tmp_path / "ding2024" / f"ding2024_{stem}.png").stat().st_size > 1000
        assert len(pd.read_csv(tmp_path / "ding2024" / f"ding2024_{stem}.csv")) > 0
    build(tmp_path)
    text = (tmp_path / "REPORT.md").read_text()
    assert "ding2024/ding2024_fig5.png" in text
    assert set(pd.read_csv(tmp_path / "summary.csv", keep_default_na=False).verdict) <= {"match", "differs", "n/a"}
