"""Build hook: the wheel carries conf/, experiments/ and data/ as package data.

The repository keeps ``conf/``, ``experiments/`` and ``data/`` at its top level (the layout
contract); a wheel maps them under ``magexp/_resources/`` (found by :mod:`magexp.paths` when
the package is not in a source checkout), with the git commit it was built from in
``magexp/_resources/commit.txt`` (``magexp --version``, provenance). Everything else is in
``pyproject.toml``.
"""

import shutil
import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

HERE = Path(__file__).resolve().parent
RESOURCES = ("conf", "experiments", "data")
SUFFIXES = {".yaml", ".yml", ".csv", ".txt", ".md", ".json"}


def git_commit() -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(HERE), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=20)
    except OSError:
        return None
    return out.stdout.strip()[:12] if out.returncode == 0 and out.stdout.strip() else None


def commit_text() -> str:
    recorded = HERE / "magexp" / "_resources" / "commit.txt"  # an sdist carries it
    return git_commit() or (recorded.read_text().strip() if recorded.exists() else "unknown")


class BuildWithResources(build_py):
    """build_py that also copies the resource folders and records the commit."""

    def run(self):
        super().run()
        if self.editable_mode:  # an editable install reads the checkout itself
            return
        target = Path(self.build_lib) / "magexp" / "_resources"
        for name in RESOURCES:
            for src in sorted((HERE / name).rglob("*")):
                if src.is_file() and src.suffix in SUFFIXES:
                    dst = target / name / src.relative_to(HERE / name)
                    dst.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copyfile(src, dst)
        target.mkdir(parents=True, exist_ok=True)
        (target / "commit.txt").write_text(commit_text() + "\n")


class SdistWithCommit(sdist):
    """sdist that records the commit (an sdist has no .git)."""

    def make_release_tree(self, base_dir, files):
        super().make_release_tree(base_dir, files)
        path = Path(base_dir) / "magexp" / "_resources" / "commit.txt"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(commit_text() + "\n")


setup(cmdclass={"build_py": BuildWithResources, "sdist": SdistWithCommit})
