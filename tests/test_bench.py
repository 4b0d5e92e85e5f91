"""The bench's bookkeeping on hand-built inputs (its timings are never tested)."""

import numpy as np
import pytest

from magexp.perf.measuring import row
from magexp.perf.peertable import reach, wilson


def test_wilson_interval_of_all_and_none():
    """20 of 20 and 0 of 20: the 95 % Wilson interval is [0.839, 1] and [0, 0.161]."""
    assert wilson(20, 20) == pytest.approx((0.8389, 1.0), abs=1e-4)
    assert wilson(0, 20) == pytest.approx((0.0, 0.1611), abs=1e-4)
    lo, hi = wilson(10, 20)
    assert lo == pytest.approx(0.2993, abs=1e-4) and hi == pytest.approx(0.7007, abs=1e-4)


def test_reach_reads_the_first_call_within_the_target():
    run = {"trace": [(50, 9.0, 0.1), (100, 2.0, 0.2), (150, 1.005, 0.3), (200, 1.0, 0.4)], "nfev": 200,
           "wall": 0.5, "fun": 1.0}
    assert reach(run, 1.01) == (150, 0.3)
    assert np.isnan(reach(run, 0.5)[0])
    closed_form = {"trace": [], "nfev": 1, "wall": 0.002, "fun": 1.0}
    assert reach(closed_form, 1.01) == (1, 0.002) and np.isnan(reach(closed_form, 0.9)[1])


def test_row_is_median_and_interquartile_range():
    r = row("m", "e", [1.0, 2.0, 3.0, 4.0, 100.0], "s")
    assert (r["value"], r["lo"], r["hi"]) == (3.0, 2.0, 4.0)
    assert np.isnan(row("m", "e", [], "s")["value"])
