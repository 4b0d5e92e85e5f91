"""Count the outcomes of the bad-input table (tests/test_bad_input.py) on a checkout.

    python tools/bad_input_table.py [CHECKOUT]

Runs the table's cases (in-process, one pytest process) against the magexp of ``CHECKOUT``
(default: this one) and prints how many are clean (one line, exit 2, nothing written), not one
line, wrote something, or a wrong result (accepted), and the cases that are not clean. Anything
the cases wrote into ``/`` is removed again afterwards, and another checkout's ``results/``
restored from git (an old checkout lets exploration write there).
"""

from __future__ import annotations

import collections
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent
CATEGORIES = ("clean", "not one line", "wrote something", "wrong result")


def main(argv: list[str]) -> int:
    checkout = Path(argv[0]).resolve() if argv else HERE
    root_before = set(os.listdir("/"))
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "table.tsv"
        env = {**os.environ, "PYTHONPATH": str(checkout), "MAGEXP_TABLE_LOG": str(log),
               "MAGEXP_CACHE": str(Path(tmp) / "cache")}
        subprocess.run([sys.executable, "-m", "pytest", str(HERE / "tests" / "test_bad_input.py"), "-q", "-n", "0",
                        "-k", "test_bad_input and not process", "-p", "no:cacheprovider", "--no-header", "-rN"],
                       cwd=checkout, env=env, stdout=subprocess.DEVNULL)
        rows = [line.rstrip("\n").split("\t", 2) for line in log.read_text().splitlines()]
    for name in set(os.listdir("/")) - root_before:  # what a case wrote into the root folder
        path = Path("/") / name
        shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
    if checkout != HERE:  # another checkout's results/, as exploration left it: restored (here, it is reported)
        subprocess.run(["git", "-C", str(checkout), "checkout", "-q", "--", "results"], check=False)
        subprocess.run(["git", "-C", str(checkout), "clean", "-fdq", "--", "results"], check=False)
    counts = collections.Counter(category for category, *_ in rows)
    for category, case, detail in rows:
        if category != "clean":
            print(f"{category:16} {case}\n{'':16} {detail[:240]}")
    print(f"\n{checkout}: {len(rows)} cases: " + ", ".join(f"{counts[c]} {c}" for c in CATEGORIES))
    print(f"cases that changed the checkout's results/: {sum('results/ changed' in detail for *_, detail in rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
