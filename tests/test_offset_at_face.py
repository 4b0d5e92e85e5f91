"""The per-run count of offset estimates on the search box's face (magexp.artifacts.plan.offset_at_face)."""

import numpy as np
import pandas as pd

from magexp.artifacts.plan import offset_at_face


def _configs(*boxes):
    return [{"scenario": {"search": {"offset": box}}} if box is not None else {"scenario": {}} for box in boxes]


def test_counts_offsets_on_either_face_of_each_runs_box():
    table = pd.DataFrame({"I1": [1000.0, -5.0, -1000.0, 499.9999], "I2": [3.0, 999.9999, 1000.0, 0.0],
                          "I3": [0.0, 1.0, 2.0, -500.0]})
    got = offset_at_face(table, _configs([-1000, 1000], [-1000, 1000], [-1000, 1000], [-500, 500]))
    # exactly on a face counts; 1e-4 nT inside a 2000 nT box does not (tolerance 1e-9 x range)
    assert got.tolist() == [1, 0, 2, 1]


def test_unknown_box_is_nan_and_no_offset_columns_is_none():
    table = pd.DataFrame({"b1": [100.0, 100.0], "b2": [0.0, 0.0], "b3": [0.0, 0.0]})
    got = offset_at_face(table, _configs([-100, 100], None))
    assert got.iloc[0] == 1 and np.isnan(got.iloc[1])
    assert offset_at_face(pd.DataFrame({"x": [1.0]}), _configs([-1, 1])) is None
    assert offset_at_face(table, _configs(None, None)) is None
