"""The Yuan 2018 artifacts run end to end at tiny sizes into a temporary folder."""

import pandas as pd
import pytest

from magexp.reproduce import reproduce_paper
from magexp.report import build


@pytest.mark.slow
def test_yuan2018_artifacts_tiny(tmp_path):
    summary = reproduce_paper("yuan2018", root=tmp_path, seeds=2, jobs=1, tiny=True, log=lambda *_: None)
    for stem in ("table2", "table3", "table4", "table5", "table7", "fig2", "fig3", "fig4", "fig6", "fig7", "fig8"):
        assert (tmp_path / "yuan2018" / f"yuan2018_{stem}.png").stat().st_size > 1000
        assert len(pd.read_csv(tmp_path / "yuan2018" / f"yuan2018_{stem}.csv")) > 0
    assert summary.setting.str.startswith("scenario=").all()
    s11 = summary[(summary.artifact == "yuan2018_table2") & (summary.quantity == "S11")
                  & (summary.estimator == "rdpso") & summary.setting.str.contains("objective=vector")]
    assert len(s11) == 1 and s11.paper_value.iloc[0] == pytest.approx(-1.6013) and s11.truth.iloc[0] == pytest.approx(-1.6)
    build(tmp_path)
    text = (tmp_path / "REPORT.md").read_text()
    assert "yuan2018/yuan2018_table3.png" in text and "mode 4" in text.lower()
