"""The wheel is a working tool: built, installed into a fresh environment, run from elsewhere.

Slow (it builds a wheel and creates a virtual environment): ``make test-full`` runs it.
The fresh environment gets magexp's dependencies from the project's environment through a
``.pth`` path entry (no download); magexp itself only from the wheel.
"""

import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from magexp.paths import ROOT, SOURCE_CHECKOUT

pytestmark = [pytest.mark.full, pytest.mark.skipif(not SOURCE_CHECKOUT, reason="needs the source checkout")]


def run(cmd, cwd, env=None):
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600,
                          env={**os.environ, **(env or {})})
    assert proc.returncode == 0, (cmd, proc.stdout[-2000:], proc.stderr[-2000:])
    return proc.stdout


def test_wheel_installs_and_runs_from_another_folder(tmp_path):
    wheels = tmp_path / "wheels"
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(ROOT), "-w", str(wheels)], cwd=tmp_path)
    (wheel,) = wheels.glob("magexp-*.whl")
    import zipfile

    names = zipfile.ZipFile(wheel).namelist()
    for needed in ("magexp/_resources/conf/config.yaml", "magexp/_resources/conf/scenario/base/yuan2018.yaml",
                   "magexp/_resources/experiments/ding2024/ding2024_fig3.yaml",
                   "magexp/_resources/data/yan2022_mockup.csv", "magexp/_resources/commit.txt",
                   "hydra_plugins/magexp_launcher/magexp_launcher.py", "magexp/_resources/conf/hydra/launcher/magexp.yaml"):
        assert needed in names, needed
    env_dir = tmp_path / "env"
    run([sys.executable, "-m", "venv", str(env_dir)], cwd=tmp_path)
    python = env_dir / "bin" / "python"
    site = Path(run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], cwd=tmp_path).strip())
    (site / "magexp_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")  # dependencies, no download
    run([str(python), "-m", "pip", "install", "-q", "--no-deps", str(wheel)], cwd=tmp_path)
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {"MAGEXP_CACHE": str(tmp_path / "cache")}
    magexp = str(env_dir / "bin" / "magexp")
    located = run([str(python), "-c", "import magexp.paths as p; print(p.CONF)"], cwd=work)
    assert str(env_dir) in located  # the installed copy, not the checkout
    assert "ding2024_exp1" in run([magexp, "--help"], cwd=work)
    version = run([magexp, "--version"], cwd=work)
    assert version.startswith("magexp ") and "commit unknown" not in version  # the commit the wheel was built from
    run([magexp, "scenario=yan2022_mockup", "estimator=ls", "hydra.run.dir=one"], cwd=work, env=env)
    assert (work / "one" / "metrics.csv").exists()
    run([magexp, "-m", "estimator=ellipsoid,lm", "hydra.sweep.dir=sweep", "hydra.launcher.jobs=1"], cwd=work, env=env)
    assert len((work / "sweep" / "sweep.csv").read_text().splitlines()) == 3
    run([str(python), "-m", "magexp.artifacts.reproduce", "yan2022", "--only", "yan2022_table_mockup", "--tiny", "--jobs", "1",
         "--out", "scratch"], cwd=work, env=env)
    assert (work / "scratch" / "yan2022" / "yan2022_table_mockup.csv").exists()
    assert sorted(p.name for p in work.iterdir()) == ["one", "scratch", "sweep"]  # nothing else written
