"""docs/calibrate.ipynb runs from top to bottom without an error (nbclient, a fresh kernel), its outputs
show the calibration, and it stays fast; skipped when the shared recording it calibrates is absent."""

import time

import pytest

from magexp.paths import ROOT, SHARED_DATA

NOTEBOOK = ROOT / "docs" / "calibrate.ipynb"


@pytest.mark.skipif(not (SHARED_DATA / "fxos8700_mag_readings.txt").is_file(), reason="shared recording absent")
@pytest.mark.full  # the notebook in a kernel (make test-full); the API calls it makes: test_calibration_api.py
def test_calibration_notebook_runs(tmp_path):
    # imported here, not at collection: Jupyter's client costs every make test worker 0.4 s to import
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    start = time.perf_counter()
    nbclient.NotebookClient(nb, timeout=60, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    seconds = time.perf_counter() - start
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))
    assert "<Calibration fxos8700_mag_readings.txt" in text and "gate passed" in text
    assert "CAL_MAG0_XOFF" in text  # the export
    figures = [o for c in nb.cells for o in c.get("outputs", []) if "image/png" in o.get("data", {})]
    assert figures, "the figure cell drew nothing"
    print(f"notebook executed in {seconds:.1f} s")
