"""The calibrate examples run as written, in the order of their page (issue 40, item 7).

Every ``magexp calibrate`` line (and ``python -m magexp.calibration.<module>``) of a shell block of
docs/calibrate.md, and of README.md, runs in one temporary clone per page with ``../shared/data`` beside
it, one after the other, the working folder the clone's: a later example finds what an earlier one wrote
(an output folder it would collide on, a file it made). Each exits 0, or 2 with one line where the line
ends with ``# refused: <why>``; a line ending with ``# template: <why>`` is not run. New sections are
picked up as they are written."""

from __future__ import annotations

import re
import subprocess

import pytest

from documented_commands import fenced_lines
from magexp.calibration.checks import check_fit
from magexp.errors import MagexpError
from magexp.paths import ROOT, SHARED_DATA, SOURCE_CHECKOUT
from test_documented_commands import bare_clone, shell_env, split_program

PAGES = ("docs/calibrate.md", "README.md")
MARKER = re.compile(r"^#\s*(template|refused):")


def examples(text: str) -> list[tuple[int, str, str | None]]:
    """``(line, command, marker)`` of every calibrate example of the page ``text``, in order (marker
    ``template``, ``refused`` or None)."""
    found = []
    for number, command, comment in fenced_lines(text):
        program, _ = split_program(command)
        if program == "magexp calibrate" or program.startswith("python -m magexp.calibration"):
            marker = MARKER.match(comment)
            found.append((number, command, marker.group(1) if marker else None))
    return found


def test_the_examples_and_their_markers_are_read_in_order():
    page = ("```bash\n.venv/bin/python -m magexp calibrate --help   # every key\nmake test\n"
            "magexp calibrate data.path=a.csv   # template: your file\n```\n\n```python\nimport magexp\n```\n\n"
            "```bash\npython -m magexp.calibration.simulate x.csv\nmagexp calibrate data.path=x.csv \\\n"
            "    folds=1   # refused: one fold\n```\n")
    assert examples(page) == [(2, ".venv/bin/python -m magexp calibrate --help", None),
                              (4, "magexp calibrate data.path=a.csv", "template"),
                              (12, "python -m magexp.calibration.simulate x.csv", None),
                              (13, "magexp calibrate data.path=x.csv folds=1", "refused")]


@pytest.mark.full  # every example of the page: a minute
@pytest.mark.skipif(not SOURCE_CHECKOUT, reason="the pages' examples run in a source checkout")
@pytest.mark.skipif(not SHARED_DATA.is_dir(), reason="the shared recordings the examples read are absent")
@pytest.mark.parametrize("page", PAGES)
def test_the_pages_calibrate_examples_run_in_order(page, tmp_path):
    found = examples((ROOT / page).read_text())
    assert found, f"{page} shows no calibrate example"
    clone, env, ran = bare_clone(tmp_path), shell_env(tmp_path), 0
    for number, command, marker in found:
        if marker == "template":
            continue
        proc = subprocess.run(["bash", "-c", command], cwd=clone, env=env, capture_output=True, text=True,
                              timeout=600)
        want = 2 if marker == "refused" else 0
        assert proc.returncode == want, (f"{page}:{number} exits {proc.returncode}, not {want}, when the page's "
                                         "examples run in order (end the line with '# template: <why>' if it cannot "
                                         "run as written)", command, proc.stderr[-1500:])
        if want:
            assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        ran += 1
    print(f"{page}: {ran} examples ran in order ({len(found) - ran} templates)")


def test_a_fit_fitted_whatever_the_estimator_is_not_named_as_an_estimator():
    """A gyro-aided fit (Levenberg-Marquardt inside, whatever estimator= is) that fails is named as the gyro
    fit, not as estimator='lm', which the user did not run."""
    cover = {"coverage_cells": 1.0, "direction_max_angle_deg": 180.0}
    with pytest.raises(MagexpError) as err:
        check_fit("r.csv", "gyro fit", False, "the maximum number of evaluations is exceeded", cover, cover)
    assert "gyro fit reports failure" in str(err.value) and "estimator=" not in str(err.value).split(":")[1]
    with pytest.raises(MagexpError, match="estimator='ipso' reports failure"):
        check_fit("r.csv", "ipso", False, "no", cover, cover)
