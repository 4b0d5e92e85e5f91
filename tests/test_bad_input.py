"""Bad input, table-driven: one line naming the value, exit 2, nothing written, through every entry point.

Each row of :data:`TABLE` is a bad input to one entry point:

* ``run`` / ``sweep``: ``magexp ARGS`` (:func:`magexp.__main__.main`, the code of ``python -m magexp``);
* ``calibrate``: ``magexp calibrate ARGS``;
* ``reproduce``: ``python -m magexp.artifacts.reproduce ARGS`` (:func:`magexp.artifacts.reproduce.main`);
* ``api``: a call of the Python API, which must raise :class:`~magexp.errors.MagexpError` of one line.

The command lines run in-process, from an empty working folder holding only the input files; a
handful more run as real processes at the end of this file. ``make test`` runs a representative subset
of the table chosen by a fixed rule (:func:`in_make_test`), ``make test-full`` every row: the table
grows without lengthening ``make test``. Every row asserts one line on stderr
(warnings count as lines), the exit code (2; 130 for Ctrl-C), the words the line must contain (the
bad value, what is allowed), and an unchanged file tree: the working folder, the
checkout's tracked ``results/`` and the filesystem root ``/``.
"""

from __future__ import annotations

import copy
import functools
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from magexp.errors import MagexpError
from magexp.run.compose import compose_config, options
from magexp.paths import RESULTS, SHARED_DATA

MOCKUP_HEADER = "# magexp-recording v1\n# unit: nT\n# angles: rad\n# field: 34425, 1961, 35898\nbx,by,bz,heading,roll,trim\n"
ROWS = "".join(f"{1000 + 37 * i},{-500 + 11 * i * i % 700},{200 + 53 * i % 900},{0.1 * i},0.01,-0.02\n"
               for i in range(12))
CALIB_HEADER = "# magexp-recording v1\n# unit: nT\nbx,by,bz\n"
_T = np.linspace(0, 20, 60)
SPHERE = np.column_stack([40 * np.cos(_T) * np.sin(_T / 7 + 0.3), 40 * np.sin(_T) * np.sin(_T / 7 + 0.3),
                          40 * np.cos(_T / 7 + 0.3)]) + [3.0, -2.0, 1.0]  # readings all around a sphere (uT)
PLAIN = "".join(f"{x:.4f} {y:.4f} {z:.4f}\n" for x, y, z in SPHERE)

FILES = {
    # recordings read by scenario=yan2022_mockup scenario.path=<file>
    "missing_column.csv": "# magexp-recording v1\n# unit: nT\nbx,by\n1,2\n",
    "text.csv": MOCKUP_HEADER + ROWS + "1,abc,3,0,0,0\n",
    "nan.csv": MOCKUP_HEADER + ROWS + "1,nan,3,0,0,0\n",
    "huge.csv": MOCKUP_HEADER + ROWS + "1e308,2,3,0,0,0\n",
    "unit.csv": MOCKUP_HEADER.replace("unit: nT", "unit: furlong") + ROWS,
    "row_length.csv": MOCKUP_HEADER + ROWS + "1,2\n",
    "no_angles.csv": "# magexp-recording v1\n# unit: nT\nbx,by,bz\n" + "".join(
        ",".join(row.split(",")[:3]) + "\n" for row in ROWS.splitlines()),
    # recordings read by magexp calibrate data.path=<file>
    "short.csv": CALIB_HEADER + "1,2,3\n4,5,6\n7,8,10\n",
    "good.csv": CALIB_HEADER + PLAIN.replace(" ", ","),  # calibrates: its refusals are the overrides'
    "plain.txt": PLAIN,
    "secret.txt": "PASSWORD=hunter2 TOKEN=abcdef\n",  # a text file that is no recording: not echoed whole
    "wrong_version.csv": "# magexp-recording v9\n# unit: nT\nbx,by,bz\n1,2,3\n",
    "empty.csv": "",
    "header_only.csv": CALIB_HEADER,
    "dup_column.csv": "# magexp-recording v1\n# unit: nT\nbx,by,bz,bx\n1,2,3,4\n",
    "bad_field.csv": "# magexp-recording v1\n# unit: nT\n# field: 1,2\nbx,by,bz\n1,2,3\n",
    "neg_reference.csv": "# magexp-recording v1\n# unit: nT\n# reference_total: -5\nbx,by,bz\n1,2,3\n",
    "shadow": "root:$6$saltsalt$swordfishHASH:19000:0:99999:7:::\n",  # a password file: its hash never echoed
    ".env": "SECRET_KEY=swordfish\nDEBUG=1\n",  # a secret on its first line
    "secret_value.csv": CALIB_HEADER + "1,2,3\n4,5,swordfish\n",  # a secret in a value
    "evil.pickle": "cio\nopen\np0\n(VPWNED\np1\nVw\np2\ntp3\nRp4\n.",  # unpickled, it creates PWNED here
    "userplain.py": "class Plain:\n    pass\n\ndef f():\n    pass\n",  # a user module with no plug-in class
}
#: a paper of one artifact that reproduces as written (``--tiny``), and its spec mistakes (issue 44 item 2):
#: each one a folder ``specs/<mistake>/`` read as ``experiments/`` (the rows patch
#: ``magexp.artifacts.paper_spec.EXPERIMENTS``), refused in one line before any run
TOY_PAPER = """title: A toy paper
headline:
  - {id: falls, text: The offset error falls with the readings, section: Sec. 1, parts: [toy_fig1.falls]}
"""
TOY_ARTIFACT = """title: Offset error against readings
kind: final
seeds: 2
base: [scenario=ding2024_exp1, estimator=ellipsoid]
grid: {scenario.n_readings: [20, 200]}
plot: {x: scenario.n_readings, metric: offset_error}
summarise: [{quantity: offset_error, metric: offset_error}]
reported:
  - {quantity: offset_error, match: {scenario.n_readings: 20}, value: 3.0, tolerance: {factor: 10, reason: toy}}
claims:
  - {id: falls, text: N^0.6 times the error is bounded, kind: threshold, metric: offset_error * scenario.n_readings ** 0.6,
     op: "<", value: 1000}
  - {id: order, text: more readings smaller error, kind: ordering, metric: offset_error,
     cells: [{scenario.n_readings: 200}, {scenario.n_readings: 20}]}
"""
SPEC_MISTAKES = {  # mistake: (file, text replaced, by)
    "unknown_column": ("toy_fig1.yaml", "metric: offset_error * scenario", "metric: offset_eror * scenario"),
    "dotted_typo": ("toy_fig1.yaml", "n_readings ** 0.6", "n_reading ** 0.6"),
    "cells_none": ("toy_fig1.yaml", "cells: [{scenario.n_readings: 200}", "cells: [{scenario.n_readings: 2000}"),
    "where_none": ("toy_fig1.yaml", 'op: "<"', 'where: {scenario.n_readings: 50}, op: "<"'),
    "where_key": ("toy_fig1.yaml", 'op: "<"', 'where: {scenario.nreadings: 20}, op: "<"'),
    "match_none": ("toy_fig1.yaml", "match: {scenario.n_readings: 20}", "match: {scenario.n_readings: 21}"),
    "headline_part": ("paper.yaml", "parts: [toy_fig1.falls]", "parts: [toy_fig1.fall]"),
}
SPECS = {f"specs/{mistake}/toy/{name}": (text.replace(old, new) if name == file else text)
         for mistake, (file, old, new) in SPEC_MISTAKES.items()
         for name, text in (("paper.yaml", TOY_PAPER), ("toy_fig1.yaml", TOY_ARTIFACT))}

BINARY = bytes(range(256)) * 4  # not UTF-8 text
ENVIRON = b"SECRET_KEY=swordfish\x00HOME=/root\x00PATH=/usr/bin\x00"  # like /proc/self/environ

DATAFLASH = SHARED_DATA / "ardupilot_test.bin"  # a real DataFlash log, damaged in the working folder

MOCKUP = ["scenario=yan2022_mockup", "estimator=ls"]
DASK = ["hydra.launcher.executor=dask"]


def R(*parts) -> str:
    """A path inside the checkout's tracked ``results/``."""
    return str(RESULTS.joinpath(*parts))


def api(**options):
    """A bad call of ``magexp.calibrate``: good readings unless ``readings`` is given."""
    import magexp

    readings = options.pop("readings", SPHERE)
    options.setdefault("unit", "uT")
    return lambda: magexp.calibrate(readings, **options)


def load(path, **options):
    from magexp.core.recordings import load_recording

    return lambda: load_recording(path, **options)


def interrupt(*args, **kwargs):
    raise KeyboardInterrupt


def no_scheduler(*args, **kwargs):
    raise MagexpError("--scheduler 'tcp://127.0.0.1:1': no Dask scheduler answers there (timed out)")


GOOD3 = np.ones((20, 3))


def magexp_calibration():
    """A calibration of good readings, accepted whatever its gate says (to be saved or exported)."""
    import magexp

    return magexp.calibrate(SPHERE, unit="uT", model="full", folds=0, accept=True)


def row(entry, args, words, code=2, patch=None):
    return (entry, args, words, code, patch)


TABLE = [
    # ---- a device or a FIFO where a recording is read: refused before it is opened (reading /dev/zero never
    # ends; opening a FIFO without a writer never returns)
    row("calibrate", ["data.path=/dev/zero", "data.unit=uT"], ["data.path='/dev/zero'", "character device", "data.path=-"]),
    row("calibrate", ["data.path=pipe.fifo", "data.unit=uT"], ["pipe.fifo", "a FIFO"]),
    row("run", ["estimator=lm", "scenario=real_fxos8700", "scenario.file=/dev/zero"], ["scenario.file='/dev/zero'",
                                                                                        "character device"]),
    row("run", ["scenario=yan2022_mockup", "scenario.path=pipe.fifo"], ["scenario.path", "a FIFO"]),
    row("api", api(readings="pipe.fifo"), ["readings=", "a FIFO"]),
    row("api", lambda: __import__("magexp").Calibration.load("pipe.fifo"), ["path=", "a FIFO"]),
    # ---- run: config groups and keys
    row("run", ["estimator=foo"], ["'foo'", "ipso"]),
    row("run", ["scenario=nope"], ["'nope'", "ding2024_exp1"]),
    row("run", ["scenario="], ["scenario=''"]),
    row("run", ["estimator="], ["estimator=''"]),
    row("run", ["scenario.nosie=2"], ["scenario.nosie", "'nosie'", "noise", "n_readings"]),  # a typo names the keys
    row("run", ["scenario.search.offsett=[0,1]"], ["offsett", "offdiag"]),
    row("run", ["estimator.n_particle=3"], ["n_particle", "n_particles"]),
    row("run", ["sed=3"], ["sed", "seed"]),
    row("run", ["objective=bogus"], ["'bogus'", "scalar"]),
    row("run", ["+foo=1"], ["foo"]),
    row("run", ["+analysis=nope"], ["+analysis=nope", "field_kalman"]),  # an optional group is added with a choice
    row("run", ["=3"], ["=3"]),
    # the simulation command has no calibration keys
    row("run", ["task=calibrate"], ["task=calibrate", "magexp calibrate"]),
    row("run", ["task=bogus"], ["task=bogus", "magexp calibrate"]),
    row("run", ["data.path=mine.txt", "data.unit=uT", "estimator=lm"], ["data.path", "magexp calibrate"]),
    row("run", ["out=scratch/"], ["out=scratch/", "magexp calibrate"]),
    # ---- run: values
    row("run", ["scenario.noise=-1"], ["-1", ">= 0"]),
    row("run", ["scenario.noise=nan"], ["nan"]),
    row("run", ["scenario.noise=inf"], ["inf"]),
    row("run", ["scenario.noise=abc"], ["scenario.noise=abc"]),
    row("run", ["scenario.noise=true"], ["scenario.noise"]),
    row("run", ["scenario.noise=1e300"], ["1e+300", "1e+15"]),
    row("run", ["scenario.noise=${nosuch}"], ["scenario.noise=${nosuch}", "interpolation"]),
    row("run", ["scenario.noise=${oc.env:HOME}"], ["scenario.noise=${oc.env:HOME}", "interpolation"]),
    row("run", ["seed=${oc.env:HOME}"], ["seed=${oc.env:HOME}", "interpolation"]),
    row("run", ["scenario.noise_kind=pink"], ["'pink'"]),
    row("run", ["scenario.field.total=-51500"], ["scenario.field.total=-51500", "> 0"]),
    row("run", ["scenario.field.total=0"], ["scenario.field.total=0", "> 0"]),
    row("run", ["scenario.field.inclination=1000"], ["inclination=1000", "[-90, 90]"]),
    row("run", ["scenario.field.inclination=-91"], ["inclination=-91", "[-90, 90]"]),
    row("run", ["scenario.field.declination=1000"], ["declination=1000", "[-180, 360]"]),
    row("run", ["scenario.errors.hard_iron=[1e308,0,0]"], ["hard_iron", "1e+308", "1e+15"]),
    row("run", ["scenario.errors.bias=[0,0,inf]"], ["bias", "inf"]),
    row("run", ["scenario.errors.soft_iron=[[0,0,0],[0,0,0],[0,0,1e300]]"], ["soft_iron", "1e+300"]),
    row("run", ["write_history=maybe"], ["write_history='maybe'", "true or false"]),
    row("run", ["write_history=2"], ["write_history=2", "true or false"]),
    row("run", ["scenario.search.offset=[-1e300,1e300]"], ["search.offset", "1e+15"]),
    row("run", ["scenario.search.diag=[2,1]"], ["search.diag", "low < high"]),
    row("run", ["scenario.search.offset=[0,inf]"], ["search.offset"]),
    row("run", ["estimator.n_particles=0"], ["n_particles=0", ">= 1"]),
    row("run", ["estimator.n_particles=-3"], ["n_particles=-3"]),
    row("run", ["estimator.n_iterations=0"], ["n_iterations=0"]),
    row("run", ["estimator.n_iterations=abc"], ["n_iterations=abc", "integer"]),  # typed: refused at compose
    row("run", ["estimator.n_particles=2.5"], ["2.5"]),
    row("run", ["estimator.velocity_clamp=-0.1"], ["velocity_clamp=-0.1"]),
    row("run", ["estimator.init.form=weird"], ["'weird'", "printed"]),
    row("run", ["scenario.n_readings=0"], ["n_readings=0"]),
    row("run", ["scenario.n_readings=-5"], ["n_readings=-5"]),
    row("run", ["scenario.n_readings=100000000"], ["n_readings=100000000", "GiB"]),  # refused up front: memory
    row("run", ["scenario.n_readings=1e8"], ["n_readings=100000000", "GiB"]),
    row("run", ["scenario.n_readings=1.5"], ["n_readings=1.5", "an integer"]),
    row("run", ["estimator=lm", "scenario.n_readings=5"], ["n_readings=5", "12 parameters"]),
    row("run", ["estimator=ellipsoid", "scenario.n_readings=11"], ["n_readings=11"]),
    row("run", ["scenario=yuan2018_mode1", "estimator=lm", "scenario.n_readings=3"], ["n_readings=3"]),
    row("run", ["scenario=yan2022_sim", "estimator=kf", "estimator.sigma2=0"], ["sigma2=0", "> 0"]),
    row("run", ["scenario=yan2022_sim", "estimator=kf", "estimator.sigma2=-5"], ["sigma2=-5"]),
    row("run", ["seed=-1"], ["seed=-1"]),
    row("run", ["seed=abc"], ["abc"]),
    row("run", ["seed=1.5"], ["seed=1.5"]),
    # ---- run: recordings read by a scenario
    row("run", [*MOCKUP, "scenario.path=missing.csv"], ["missing.csv", "does not exist"]),
    row("run", [*MOCKUP, "scenario.path=a_folder"], ["a_folder", "is a directory"]),
    row("run", [*MOCKUP, "scenario.path=binary.csv"], ["binary.csv", "not UTF-8"]),
    row("run", [*MOCKUP, "scenario.path=environ"], ["environ", "not a text file"]),
    row("run", [*MOCKUP, "scenario.path=huge.csv"], ["1e308", "1e+15"]),
    row("run", [*MOCKUP, "scenario.path=missing_column.csv"], ["bz"]),
    row("run", [*MOCKUP, "scenario.path=text.csv"], ["abc"]),
    row("run", [*MOCKUP, "scenario.path=nan.csv"], ["nan"]),
    row("run", [*MOCKUP, "scenario.path=unit.csv"], ["furlong"]),
    row("run", [*MOCKUP, "scenario.path=row_length.csv"], ["row_length.csv"]),
    row("run", [*MOCKUP, "scenario.path=no_angles.csv"], ["heading"]),
    # ---- run: output folders, checked before any computation
    row("run", ["hydra.run.dir=a_file"], ["a_file", "is a file"]),
    row("run", ["hydra.run.dir=a_file/run"], ["a_file", "is a file"]),
    row("run", ["hydra.run.dir=/proc/magexp-run"], ["/proc/magexp-run", "not writable"]),
    row("run", ["hydra.run.dir=/"], ["hydra.run.dir='/'", "root folder"]),
    row("run", ["hydra.run.dir="], ["hydra.run.dir=''", "name a folder"]),
    row("run", [f"hydra.run.dir={R('myrun')}"], ["myrun", "inside results/"]),
    row("run", [f"hydra.run.dir={R()}"], ["inside results/"]),
    row("run", [f"hydra.run.dir={R('yan2022')}"], ["yan2022", "inside results/"]),
    row("run", [f"hydra.run.dir={R('..', 'results', 'x')}"], ["inside results/"]),
    row("run", ["hydra.run.dir=results_link/x"], ["results_link/x", "inside results/"]),  # a link into results/
    row("run", ["hydra.run.dir=results/myrun"], ["results/myrun", "inside results/"]),
    row("run", ["estimator=ellipsoid", "hydra.run.dir=results"], ["inside results/"]),
    # ---- run: the command line itself
    row("run", ["--bogus"], ["'--bogus'"]),
    row("run", ["--cfg", "foo"], ["--cfg", "'foo'", "job"]),
    row("run", ["--cfg"], ["--cfg needs a value"]),
    row("run", ["--config-name", "nosuch"], ["--config-name", "'nosuch'", "config"]),
    row("run", ["-cn", "nosuch"], ["'nosuch'"]),
    row("run", ["--config-dir", "no_such_dir"], ["no_such_dir"]),
    # ---- every bad input one line (issue 34 item 4): singular setups, tolerances, labels, silent keys
    row("run", ["estimator=lm", "scenario.errors.scale=[0,1,1]"], ["errors.scale=", "non-zero"]),
    row("run", ["estimator=lm", "scenario.errors.scale=[1,1,0]"], ["errors.scale=", "non-zero"]),
    row("run", ["estimator=lm", "scenario.errors.nonorthogonality_deg=[90,0,0]"], ["nonorthogonality_deg", "singular"]),
    row("run", ["estimator=lm", "scenario.errors.soft_iron=[[-1,0,0],[0,0,0],[0,0,0]]"], ["soft_iron", "singular"]),
    row("run", ["estimator=lm", "estimator.tol=0"], ["estimator.tol=0", "machine epsilon"]),
    row("run", ["estimator=lm", "estimator.tol=-1"], ["estimator.tol=-1"]),
    row("run", ["estimator=ml_scalar", "estimator.tol=0"], ["estimator.tol=0"]),
    row("run", ["estimator=triangular", "estimator.tol=-1"], ["estimator.tol=-1"]),
    row("run", ["estimator=lm", "estimator.tol=nan"], ["estimator.tol=nan"]),
    row("run", ["estimator=lm", "estimator.name=ipso"], ["estimator.name='ipso'", "LevenbergMarquardt", "estimator=ipso"]),
    row("run", ["estimator=ellipsoid", "estimator.name=lm"], ["estimator.name='lm'", "estimator=lm"]),
    row("run", ["--config-name", "calibrate"], ["--config-name", "'calibrate'", "config"]),
    row("calibrate", ["data.path=good.csv", "estimator=lm", "estimator.tol=nan"], ["estimator.tol=nan"]),
    row("calibrate", ["data.path=good.csv", "field.model=foo"], ["field.model='foo'", "igrf"]),
    # ---- say where, not what: file, line, column and what was expected; never a secret (issue 34)
    row("calibrate", ["data.path=shadow"], ["shadow line 1, column 1", "found 'r'", "magexp-recording v1"]),
    row("calibrate", ["data.path=.env", "data.unit=uT"], [".env line 1, column 1", "found 'S'"]),
    row("calibrate", ["data.path=secret_value.csv"], ["secret_value.csv line 5", "bz=", "not a number"]),
    row("run", ["scenario=yan2022_mockup", "estimator=ls", "scenario.path=.env"], [".env line 1, column 1"]),
    # ---- results/ is the canonical reproduction's alone, whatever a path's interpolations resolve to (issue 34)
    row("run", ["estimator=lm", "hydra.run.dir=${oc.env:HOME}"], ["hydra.run.dir='${oc.env:HOME}'", "interpolations"]),
    row("run", ["hydra.run.dir=${hydra:runtime.cwd}/results/x"], ["interpolations"]),
    row("run", ["+hydra.run.dir=results/x"], ["hydra.run.dir='results/x'", "inside results/"]),
    row("run", ["~hydra.run.dir"], ["~hydra.run.dir", "name a folder"]),
    row("run", ["hydra.run.dir=a,b"], ["hydra.run.dir='a,b'", "quote", "'a,b'"]),
    row("run", ["hydra.run.dir=a=b"], ["hydra.run.dir='a=b'", "quote"]),
    row("run", [f"hydra.run.dir='{R('x,y')}'"], ["inside results/"]),  # quoted for Hydra, still checked
    row("run", ["estimator=lm"], ["MAGEXP_CACHE", "inside results/"], patch=[("magexp.paths.CACHE", RESULTS / "c")]),
    row("sweep", ["-m", "estimator=lm", "seed=0,1", "hydra.sweep.dir=${oc.env:HOME}"], ["interpolations"]),
    row("sweep", ["-m", "estimator=lm", "hydra.sweep.dir=${hydra:runtime.cwd}/results/x"], ["interpolations"]),
    row("sweep", ["-m", "estimator=lm", "++hydra.sweep.dir=${hydra:runtime.cwd}/results/x"], ["interpolations"]),
    row("sweep", ["-m", "estimator=lm", "hydra.sweep.dir=a,b"], ["hydra.sweep.dir='a,b'", "quote"]),
    row("sweep", ["-m", "estimator=lm", "hydra.sweep.dir=[a]"], ["hydra.sweep.dir='[a]'", "quote"]),
    row("sweep", ["-m", "estimator=lm", "hydra.sweep.dir='results/x'"], ["inside results/"]),
    row("calibrate", ["data.path=good.csv"], ["MAGEXP_CACHE", "inside results/"],
        patch=[("magexp.paths.CACHE", RESULTS / "cache")]),
    row("api", lambda: magexp_calibration().save(R("calibration.json")), ["path=", "inside results/"]),
    row("api", lambda: magexp_calibration().export("ardupilot", R()), ["export path=", "inside results/"]),
    row("api", lambda: magexp_calibration().export("ros", R("ros.yaml")), ["export path=", "inside results/"]),
    # ---- bounded before it starts: processes by the cores (issue 34)
    row("reproduce", ["ding2024", "--jobs", "1000000"], ["--jobs 1000000", "cores"]),
    row("reproduce", ["ding2024", "--jobs", "1e20"], ["--jobs", "'1e20'"]),
    row("sweep", ["-m", "estimator=lm", "hydra.launcher.jobs=1000000"], ["hydra.launcher.jobs=1000000", "cores"]),
    row("run", ["scenario=yuan2018_mode1", "estimator=lm", "scenario.rotation.sample_period=1e-10"],
        ["sample_period=1e-10", "MAGEXP_MAX_READINGS"]),
    row("run", ["estimator.init.burn_in=1e12"], ["burn_in=", "MAGEXP_MAX_RUN_WORK"]),
    row("run", ["estimator.init.burn_in=-1"], ["burn_in=-1", "integer >= 0"]),
    row("run", ["estimator.init.burn_in=2.5"], ["burn_in=2.5", "integer"]),
    row("run", ["scenario=real_fxos8700", "estimator=lm", "scenario.folds=100000000"], ["folds=100000000", "readings"]),
    row("run", ["scenario=real_fxos8700", "estimator=lm", "scenario.folds=2.5"], ["folds=2.5", "integer"]),
    row("run", ["scenario=real_fxos8700", "estimator=lm", "scenario.heldout_fold=2.5"], ["heldout_fold=2.5"]),
    # ---- no code from a file or an override (issue 34): refused before anything is imported or called
    row("run", ["--experimental-rerun", "evil.pickle"], ["--experimental-rerun", "unpickles"]),
    row("run", ["--cfg", "job", "--experimental-rerun", "evil.pickle"], ["--experimental-rerun"]),
    row("run", ["--config-dir", "a_folder"], ["--config-dir", "conf/"]),
    row("run", ["-cp", "a_folder"], ["-cp", "conf/"]),
    row("run", ["estimator._target_=os.system"], ["estimator._target_='os.system'", "no class"]),
    row("run", ["estimator=lm", "estimator._target_=numpy.savetxt"], ["'numpy.savetxt'"]),
    row("run", ["scenario._target_=subprocess.Popen"], ["scenario._target_='subprocess.Popen'"]),
    row("run", ["estimator._target_=magexp.run.cache.write"], ["'magexp.run.cache.write'", "not a class"]),
    row("run", ["estimator._target_=magexp.run.sweep.SweepTable"], ["SweepTable", "plug-in"]),
    row("run", ["estimator._target_=magexp.estimators.lm.EllipsoidFit.fit"], ["EllipsoidFit.fit", "cannot be imported"]),
    row("run", ["scenario._target_=magexp.core.dataset.Dataset"], ["Dataset", "plug-in"]),
    row("run", ["estimator._target_=userplain.f"], ["'userplain.f'"]),
    row("run", ["estimator._target_=setup.X"], ["'setup.X'"]),
    row("run", ["estimator._target_=os"], ["estimator._target_='os'", "dotted name"]),
    row("run", ["estimator.velocity._target_=builtins.exec"], ["estimator.velocity._target_='builtins.exec'"]),
    row("run", ["estimator.velocity={_target_:os.system,command:id}"], ["estimator.velocity._target_='os.system'"]),
    row("run", ["+hydra.callbacks.x._target_=numpy.savetxt"], ["hydra.callbacks.x._target_", "SweepTable"]),
    row("run", ["hydra.job.env_set.LD_PRELOAD=x.so"], ["hydra.job.env_set.LD_PRELOAD", "not allowed"]),
    row("run", ["+hydra.searchpath=[file://a_folder]"], ["+hydra.searchpath", "not allowed"]),
    row("calibrate", ["data.path=good.csv", "estimator._target_=os.system"],
        ["estimator._target_='os.system'"]),
    row("calibrate", ["data.path=good.csv", "estimator=lm", "estimator._target_=shutil.rmtree"],
        ["'shutil.rmtree'"]),
    row("sweep", ["-m", "estimator=lm", "+hydra.callbacks.x._target_=numpy.savetxt",
                  f"+hydra.callbacks.x.fname={R('summary.csv')}", "+hydra.callbacks.x.X=[0]"],
        ["hydra.callbacks.x", "not allowed"]),
    row("sweep", ["-m", "estimator=lm", "hydra.launcher._target_=os.getpid"], ["hydra.launcher._target_='os.getpid'",
                                                                               "MagexpLauncher"]),
    row("sweep", ["-m", "estimator=lm", "hydra.sweeper._target_=os.getpid"], ["'os.getpid'", "MagexpSweeper"]),
    row("sweep", ["-m", "hydra.callbacks.sweep_table._target_=os.getpid"], ["sweep_table._target_='os.getpid'"]),
    row("sweep", ["-m", "hydra.launcher={_target_:os.getpid}"], ["hydra.launcher._target_='os.getpid'"]),
    row("sweep", ["-m", "+hydra.job_logging.handlers.x.class=os.system"], ["hydra.job_logging", "not allowed"]),
    row("sweep", ["-m", "+hydra.sweeper.params.estimator._target_=os.system"], ["_target_"]),
    row("sweep", ["-m", "seed=0,1", "estimator._target_=os.system"], ["'os.system'"]),
    row("run", ["--cfg", "job", "scenario.nosie=1"], ["'nosie'"]),
    row("run", ["scenario.noise=1,2"], ["needs -m"]),
    row("run", ["hydra.job.chdir=true"], ["hydra.job.chdir"]),
    row("run", ["scenario.noise=[1"], ["could not parse"]),
    # ---- sweeps: every value checked before the first job (and no multirun folder)
    row("sweep", ["-m", "estimator=pso,bogus"], ["'bogus'"]),
    row("sweep", ["-m", "scenario.noise=2,-1", "seed=range(3)"], ["scenario.noise=-1"]),
    row("sweep", ["-m", "scenario.noise=1,2", "seed=0,1,-4"], ["seed=-4"]),
    row("sweep", ["-m", "estimator=lm,ellipsoid", "scenario.n_readings=300,6"], ["n_readings=6"]),
    row("sweep", ["-m", "seed=range(2)", "scenario.nosie=1,2"], ["'nosie'"]),
    row("sweep", ["-m", "scenario.field.inclination=0,1000"], ["inclination=1000"]),
    row("sweep", ["-m", "scenario.noise=1,${nosuch}"], ["${nosuch}", "interpolation"]),
    row("sweep", ["-m", "write_history=true,maybe"], ["write_history='maybe'"]),
    row("sweep", ["-m", "estimator=glob(zzz*)"], ["estimator=glob(zzz*)", "no job", "ipso"]),
    row("sweep", ["-m", "seed=range(0,0)"], ["seed=range(0,0)", "no job"]),
    row("sweep", ["-m", "hydra/launcher=nope", "seed=1,2"], ["'nope'", "joblib"]),
    row("sweep", ["-m", "hydra.launcher.foo=1", "seed=1,2"], ["hydra.launcher.foo"]),
    row("sweep", ["-m", "hydra.launcher.jobs=abc", "seed=1,2"], ["hydra.launcher.jobs", "abc"]),
    row("sweep", ["-m", "hydra.launcher.jobs=-2", "seed=1,2"], ["hydra.launcher.jobs", "-2"]),
    row("sweep", ["-m", "hydra.launcher.executor=nope", "seed=1,2"], ["hydra.launcher.executor", "'nope'", "dask"]),
    row("sweep", ["-m", "hydra.launcher.scheduler=slurm", "seed=1,2"], ["hydra.launcher.scheduler", "executor=dask"]),
    row("sweep", ["-m", *DASK, "hydra.launcher.scheduler=localhost", "seed=1,2"], ["'localhost'", "PORT"]),
    row("sweep", ["-m", *DASK, "hydra.launcher.scheduler=tcp://node1", "seed=1,2"], ["'tcp://node1'", "PORT"]),
    row("sweep", ["-m", *DASK, "hydra.launcher.scheduler=tcp://node1:99999", "seed=1,2"], ["99999", "PORT"]),
    row("sweep", ["-m", *DASK, "hydra.launcher.scheduler=tcp://127.0.0.1:1", "seed=1,2"], ["no Dask scheduler"],
        patch=[("magexp.run.executors.DaskExecutor.__init__", no_scheduler)]),
    row("sweep", ["-m", "estimator=ellipsoid", "seed=1,2"], ["interrupted"], code=130,
        patch=[("magexp.run.sweep.run_many", interrupt)]),
    row("sweep", ["-m", "hydra.sweep.dir=a_file", "seed=1,2"], ["a_file", "is a file"]),
    row("sweep", ["-m", "hydra.sweep.dir=", "seed=1,2"], ["hydra.sweep.dir=''", "name a folder"]),
    row("sweep", ["-m", "hydra.sweep.dir=/", "seed=1,2"], ["'/'", "root folder"]),
    row("sweep", ["-m", f"hydra.sweep.dir={R('mysweep')}", "seed=1,2"], ["mysweep", "inside results/"]),
    row("sweep", ["-m", f"hydra.sweep.dir={R()}", "seed=1,2"], ["inside results/"]),
    row("sweep", ["-m", "hydra.sweep.dir=results_link/s", "seed=1,2"], ["inside results/"]),
    row("sweep", ["-m", "hydra.sweep.dir=results/mysweep", "seed=1,2"], ["results/mysweep", "inside results/"]),
    row("sweep", ["-m", "hydra.sweep.subdir=../../../escaped_${hydra.job.num}", "seed=1,2"],
        ["hydra.sweep.subdir", "'..'"]),
    row("sweep", ["-m", "hydra.sweep.subdir=/tmp/escaped_${hydra.job.num}", "seed=1,2"], ["hydra.sweep.subdir"]),
    row("sweep", ["-m", "hydra.sweep.subdir=", "seed=1,2"], ["hydra.sweep.subdir=''"]),
    row("sweep", ["-m", "hydra.sweep.subdir=same", "seed=1,2", "hydra.launcher.jobs=1"],
        ["hydra.sweep.subdir='same'", "share a folder"]),
    row("sweep", ["-m", "hydra.sweep.subdir=${hydra.job.override_dirname}", "scenario.name=../../../up,x",
                  "hydra.launcher.jobs=1"], ["hydra.sweep.subdir", "inside the sweep's folder"]),
    # ---- calibrate
    row("calibrate", [], ["data.path=None", "data.path=<recording file>"]),
    row("calibrate", ["mine.csv"], ["'mine.csv'", "KEY=VALUE"]),
    row("calibrate", ["data.path=missing.csv", "data.unit=nT"], ["missing.csv"]),
    row("calibrate", ["data.path="], ["data.path"]),
    row("calibrate", ["data.path=a_folder"], ["a_folder", "directory"]),
    row("calibrate", ["data.path=missing_column.csv"], ["bz"]),
    row("calibrate", ["data.path=text.csv"], ["abc"]),
    row("calibrate", ["data.path=nan.csv"], ["nan"]),
    row("calibrate", ["data.path=short.csv", "estimator=lm"], ["3"]),
    row("calibrate", ["data.path=unit.csv"], ["furlong"]),
    row("calibrate", ["data.path=row_length.csv"], ["row_length.csv"]),
    row("calibrate", ["data.path=binary.csv"], ["binary.csv", "not UTF-8"]),
    row("calibrate", ["data.path=environ"], ["environ", "not a text file"]),
    row("calibrate", ["data.path=secret.txt"], ["secret.txt", "magexp-recording v1"]),
    row("calibrate", ["data.path=wrong_version.csv"], ["wrong_version.csv", "magexp-recording v1"]),
    row("calibrate", ["data.path=empty.csv"], ["empty.csv"]),
    row("calibrate", ["data.path=header_only.csv"], ["header_only.csv"]),
    row("calibrate", ["data.path=dup_column.csv"], ["bx"]),
    row("calibrate", ["data.path=bad_field.csv"], ["field"]),
    row("calibrate", ["data.path=neg_reference.csv"], ["reference_total"]),
    row("calibrate", ["data.path=plain.txt"], ["data.unit=None", "give data.unit"]),
    row("calibrate", ["data.path=plain.txt", "data.unit=furlong"], ["'furlong'", "uT"]),
    row("calibrate", ["data.path=good.csv", "data.unit=uT"], ["data.unit='uT'", "nT"]),
    row("calibrate", ["data.path=plain.txt", "data.unit=µT", "data.format=nope"], ["data.format='nope'"]),
    row("calibrate", ["data.path=good.csv", "data.mag_axes=q,r,s"], ["mag_axes"]),
    row("calibrate", ["data.path=good.csv", "data.reference_total=abc"], ["reference_total='abc'", "> 0"]),
    row("calibrate", ["data.path=good.csv", "data.reference_total=-1"], ["reference_total=-1", "> 0"]),
    row("calibrate", ["data.path=good.csv", "data.reference_total=1e308"], ["reference_total=1e+308", "1e+15"]),
    # a live stream (magexp.calibration.live): refused before anything is read
    row("calibrate", ["data.path=-", "live.margin=1"], ["live.margin=1", "0 <= margin < 1"]),
    row("calibrate", ["data.path=-", "live.stall_seconds=0"], ["live.stall_seconds=0", "> 0"]),
    row("calibrate", ["data.serial=/dev/tty0", "data.path=good.csv"], ["data.path='good.csv'", "data.serial"]),
    row("calibrate", ["data.serial=/dev/magexp-no-such-port"], ["data.serial='/dev/magexp-no-such-port'"]),
    row("calibrate", ["data.path=good.csv", "folds=abc"], ["folds='abc'", "integer >= 0"]),
    row("calibrate", ["data.path=good.csv", "folds=-1"], ["folds=-1", "integer >= 0"]),
    row("calibrate", ["data.path=good.csv", "folds=2.5"], ["folds=2.5", "integer >= 0"]),
    row("calibrate", ["data.path=good.csv", "folds=${nosuch}"], ["folds=${nosuch}", "interpolation"]),
    row("calibrate", ["data.path=${oc.env:HOME}"], ["data.path=${oc.env:HOME}", "interpolation"]),
    row("calibrate", ["data.path=good.csv", "seed=-1"], ["seed=-1"]),
    row("calibrate", ["data.path=good.csv", "seed=abc"], ["seed='abc'"]),
    row("calibrate", ["data.path=good.csv", "objective=nope"], ["objective='nope'", "scalar"]),
    row("calibrate", ["data.path=good.csv", "objective=vector"], ["'vector'", "choose one of"]),
    row("calibrate", ["data.path=good.csv", "model=nope"], ["model='nope'", "full"]),
    row("calibrate", ["data.path=good.csv", "estimator=nope"], ["nope", "ellipsoid"]),
    row("calibrate", ["data.path=good.csv", "estimator=kf"], ["estimator='kf'", "ellipsoid"]),
    row("calibrate", ["data.path=good.csv", "estimator=ipso", "estimator.n_particles=0"], ["n_particles=0"]),
    row("calibrate", ["data.path=good.csv", "foo=1"], ["foo"]),
    row("calibrate", ["data.path=good.csv", "igrf.latitude=100", "igrf.longitude=0", "igrf.date=2020-01-01"],
        ["latitude"]),
    row("calibrate", ["data.path=good.csv", "igrf.latitude=10", "igrf.longitude=0", "igrf.date=someday"],
        ["someday"]),
    row("calibrate", ["data.path=good.csv", "out=a_file"], ["a_file"]),
    row("calibrate", ["data.path=good.csv", "out=a_file/sub"], ["a_file"]),
    row("calibrate", ["data.path=good.csv", "out=taken"], ["taken", "already holds"]),
    row("calibrate", ["data.path=good.csv", f"out={R('mine')}"], ["results/"]),
    row("calibrate", ["data.path=good.csv", f"out={R()}"], ["results/"]),
    row("calibrate", ["data.path=good.csv", "out=/"], ["out='/'", "root folder"]),
    row("calibrate", ["data.path=good.csv", "out="], ["out=''", "name a folder"]),
    row("calibrate", ["data.path=good.csv", "out=results_link/c"], ["results/"]),
    row("calibrate", ["data.path=good.csv", "out=results/calibration"], ["results/"]),
    # ---- reproduce
    row("reproduce", ["nopaper"], ["'nopaper'", "ding2024"]),
    row("reproduce", [], ["paper"]),
    row("reproduce", ["ding2024", "--bogus"], ["--bogus"]),
    row("reproduce", ["ding2024", "--jobs", "-1"], ["--jobs -1"]),
    row("reproduce", ["ding2024", "--jobs", "abc"], ["--jobs", "'abc'"]),
    row("reproduce", ["ding2024", "--jobs", "1.5"], ["--jobs", "'1.5'"]),
    row("reproduce", ["ding2024", "--seeds", "0", "--out", "res"], ["--seeds 0"]),
    row("reproduce", ["ding2024", "--seeds", "-3", "--out", "res"], ["--seeds -3"]),
    row("reproduce", ["ding2024", "--seeds", "abc", "--out", "res"], ["--seeds", "'abc'"]),
    row("reproduce", ["ding2024", "--only"], ["--only"]),
    row("reproduce", ["ding2024", "--only", "nothing"], ["'nothing'"]),
    row("reproduce", ["ding2024", "--executor", "nope"], ["--executor 'nope'", "dask"]),
    row("reproduce", ["ding2024", "--scheduler", "tcp://h:1"], ["--scheduler", "needs --executor dask"]),
    row("reproduce", ["ding2024", "--executor", "dask", "--scheduler", "localhost"], ["'localhost'", "PORT"]),
    row("reproduce", ["ding2024", "--only", "ding2024_fig3", "--out", "a_file"], ["a_file", "is a file"]),
    row("reproduce", ["ding2024", "--only", "ding2024_fig3", "--out", "/proc/magexp-results"],
        ["/proc/magexp-results", "not writable"]),
    row("reproduce", ["all", "--out", "a_file/results"], ["a_file", "is a file"]),
    row("reproduce", ["ding2024", "--tiny"], ["--tiny", "results/"]),
    row("reproduce", ["ding2024", "--seeds", "2"], ["--seeds", "results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--tiny", "--out", R("yan2022")],
        ["--out", "yan2022", "inside results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--seeds", "2", "--out", R("explore")],
        ["explore", "inside results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--out", R("yan2022")], ["yan2022", "inside results/"]),
    row("reproduce", ["yan2022", "--redraw", "--out", R("yan2022")], ["yan2022", "inside results/"]),
    row("reproduce", ["yan2022", "--tiny", "--out", R("..", "results")], ["--tiny", "results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--tiny", "--out", "results/yan2022"],
        ["results/yan2022", "inside results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--seeds", "2", "--out", "results/explore"],
        ["results/explore", "inside results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--seeds", "2", "--out", "results"], ["--seeds", "results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--tiny", "--out", "results_link"], ["--tiny", "results/"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--tiny", "--out", "/"], ["'/'", "root folder"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--tiny", "--out", ""], ["--out=''", "name a folder"]),
    row("reproduce", ["yan2022", "--redraw", "--out", "fresh"], ["--redraw", "does not exist"]),
    row("reproduce", ["yan2022", "--only", "yan2022_fig3", "--tiny", "--out", "fresh"], ["interrupted"], code=130,
        patch=[("magexp.artifacts.reproduce.run_many", interrupt)]),
    # ---- the Python API
    row("api", api(readings=np.ones((20, 3)) + 1j), ["complex"]),
    row("api", api(readings=np.ma.masked_array(np.ones((20, 3)), mask=np.zeros((20, 3)))), ["masked"]),
    row("api", api(readings=[["a", "b", "c"]] * 20), ["readings", "number"]),
    row("api", api(readings=[[None, 1, 2]] * 20), ["readings", "finite"]),
    row("api", api(readings=[[1, 2, 3], [1, 2]]), ["readings"]),
    row("api", api(readings=object()), ["readings"]),
    row("api", api(readings=np.ones(20)), ["shape (20,)"]),
    row("api", api(readings=np.ones((20, 2))), ["shape (20, 2)"]),
    row("api", api(readings=np.full((20, 3), np.nan)), ["NaN"]),
    row("api", api(readings=np.full((20, 3), 1e308)), ["1e+15"]),
    row("api", api(readings=np.ones((5, 3))), ["5 readings", "at least 12"]),
    row("api", api(readings=GOOD3), ["readings"]),  # identical readings: degenerate
    row("api", api(unit=None), ["unit=None"]),
    row("api", api(unit="furlong"), ["'furlong'", "uT"]),
    row("api", api(estimator="nope"), ["estimator='nope'", "ellipsoid"]),
    row("api", api(estimator=42), ["estimator=42", "ellipsoid"]),
    row("api", api(estimator="kf"), ["estimator='kf'"]),
    row("api", api(estimator="lm", nosuch_option=1), ["nosuch_option", "max_nfev"]),
    row("api", api(estimator="ipso", n_particles=0), ["n_particles=0"]),
    row("api", api(objective="nope"), ["objective='nope'", "scalar"]),
    row("api", api(objective="vector"), ["'vector'", "choose one of"]),
    row("api", api(model="nope"), ["model='nope'", "full"]),
    row("api", api(folds=-1), ["folds=-1", "integer >= 0"]),
    row("api", api(folds=2.5), ["folds=2.5", "integer >= 0"]),
    row("api", api(folds="abc"), ["folds='abc'", "integer >= 0"]),
    row("api", api(seed=-1), ["seed=-1"]),
    row("api", api(seed="abc"), ["seed='abc'"]),
    row("api", api(seed=1.5), ["seed=1.5"]),
    row("api", api(reference_total=-1), ["reference_total=-1", "> 0"]),
    row("api", api(reference_total="abc"), ["reference_total='abc'"]),
    row("api", api(reference_total=1e308), ["reference_total=1e+308", "1e+15"]),
    row("api", api(readings="missing.csv"), ["missing.csv", "does not exist"]),
    row("api", api(readings="environ"), ["environ", "not a text file"]),
    row("api", api(readings="secret.txt"), ["secret.txt"]),
    row("api", load("binary.csv"), ["binary.csv", "not UTF-8"]),
    row("api", load("plain.txt", unit="µ"), ["unit='µ'"]),
    row("api", load("good.csv", format="nope"), ["data.format='nope'"]),
    # ---- the last silent and multi-line cases of issue 34: zeros no key allows, implausible rates, a
    #      binary file and a damaged log (one line each), every field.* value, a bool that must be a bool
    row("run", ["estimator=pso", "estimator.velocity_clamp=0"], ["velocity_clamp=0", "> 0", "unbounded"]),
    row("run", ["estimator=ipso", "estimator.velocity_clamp=0"], ["velocity_clamp=0", "> 0"]),
    row("run", ["estimator=pso9", "estimator.velocity_clamp=-1"], ["velocity_clamp=-1"]),
    row("run", ["estimator=rdpso", "estimator.velocity_clamp=0"], ["velocity_clamp=0", "> 0"]),
    row("run", ["estimator=rdpso", "estimator.velocity_limit=0"], ["velocity_limit=0", "> 0"]),
    row("run", ["estimator=ipso", "estimator.velocity.c1.start=-1"], ["velocity.c1.start=-1", ">= 0"]),
    row("run", ["scenario=yuan2018_mode1", "estimator=ekf", "estimator.r=0"], ["estimator.r=0", "> 0"]),
    row("run", ["scenario=yuan2018_mode1", "estimator=ekf", "estimator.r=-1"], ["estimator.r=-1"]),
    row("run", ["scenario=yan2022_sim", "estimator=kf", "estimator.offset_scale=0"], ["offset_scale=0", "> 0"]),
    row("run", ["estimator=ellipsoid_specific", "estimator.k=0"], ["estimator.k=0", "> 0"]),
    row("run", ["scenario=yuan2018_adis16488", "estimator=lm", "scenario.gyro.noise_deg_s=1e12"],
        ["scenario.gyro.noise_deg_s=1e+12", "<= 4000", "full-scale"]),
    row("run", ["scenario=yuan2018_mode1", "estimator=lm", "scenario.gyro.drift_deg_h=1e12"], ["drift_deg_h=1e+12"]),
    row("run", ["scenario=yuan2018_mode2", "estimator=lm", "scenario.rotation.partial_arc_deg=-1"],
        ["partial_arc_deg=-1"]),
    row("run", ["scenario=real_fxos8700", "estimator=lm", "scenario.bias_bound_deg_s=abc"], ["bias_bound_deg_s=abc", "number"]),
    row("run", ["scenario=real_xio_fusion", "estimator=lm", "scenario.bias_bound_deg_s=-1"], ["bias_bound_deg_s=-1"]),
    row("calibrate", ["data.path=random.bin"], ["random.bin", "no DataFlash log", "byte 0"]),
    row("calibrate", ["data.path=random.bin", "data.format=dataflash"], ["random.bin", "byte 0"]),
    row("calibrate", ["data.path=flipped.bin"], ["flipped.bin", "damaged at byte"]),
    *(row("calibrate", ["data.path=good.csv", *args], words) for args, words in [
        (["field.model=42"], ["field.model=42", "igrf, wmm"]),
        (["field.date=someday"], ["field.date='someday'", "YYYY-MM-DD"]),
        (["field.date=2020-13-01"], ["field.date='2020-13-01'"]),
        (["field.date=true"], ["field.date=True"]),
        (["field.date=2200-01-01"], ["field.date='2200-01-01'", "1900 to 2030"]),
        (["field.model=wmm", "field.date=2000-01-01"], ["field.date='2000-01-01'", "model=wmm"]),
        (["field.latitude=abc"], ["field.latitude='abc'", "[-90, 90]"]),
        (["field.latitude=100"], ["field.latitude=100"]),
        (["field.latitude=nan"], ["field.latitude=nan"]),
        (["field.longitude=500"], ["field.longitude=500", "[-180, 360]"]),
        (["field.longitude=abc"], ["field.longitude='abc'"]),
        (["field.longitude=inf"], ["field.longitude=inf"]),
        (["field.altitude_km=abc"], ["field.altitude_km='abc'", "35786"]),
        (["field.altitude_km=nan"], ["field.altitude_km=nan"]),
        (["field.altitude_km=-1e9"], ["field.altitude_km=", "[-11, 35786]"]),
        (["field.latitude=10", "field.longitude=10", "field.date=2020-01-01", "field.altitude_km=1e9"],
         ["field.altitude_km="]),
        (["data.reference_total=50", "field.longitude=999"], ["field.longitude=999"]),  # unused, still refused
        (["igrf.date=someday"], ["igrf.date='someday'"]),
        (["igrf.altitude_km=abc"], ["igrf.altitude_km='abc'"]),
        (["igrf.longitude=999"], ["igrf.longitude=999"]),
        (["counts_nt=abc"], ["counts_nt='abc'", "> 0"]),
        (["counts_nt=-1"], ["counts_nt=-1"]),
        (["max_rotation_deg=-1"], ["max_rotation_deg=-1", "[0, 180]"]),
        (["max_rotation_deg=abc"], ["max_rotation_deg='abc'"]),
        (["auto_margin=-1"], ["auto_margin=-1", "[0, 1)"]),
        (["auto_margin=nan"], ["auto_margin=nan"]),
        (["auto_margin=1"], ["auto_margin=1"]),
        (["accept=yes"], ["accept='yes'", "true"]),
        (["accept=2"], ["accept=2"]),
    ]),
    row("api", api(accept="yes"), ["accept='yes'", "true or"]),
    row("api", api(checks="no"), ["checks='no'"]),
    row("api", api(accept=1), ["accept=1"]),
    row("api", api(checks=None), ["checks=None"]),
    row("api", api(model="full", auto_margin=-1), ["auto_margin=-1"]),
    row("api", api(auto_margin="abc"), ["auto_margin='abc'"]),
    row("api", api(gate="abc"), ["gate='abc'", "mapping"]),
    row("api", api(gate={"max_rms_mG": -1}), ["gate.max_rms_mG=-1"]),
    row("api", api(gate={"nosuch": 1}), ["gate.nosuch=1"]),
    row("api", api(reference_total=True), ["reference_total=True"]),
    row("api", api(reference_total=[1, 2]), ["reference_total=[1, 2]"]),
    row("api", api(model=None), ["model=None"]),
    row("api", api(objective=None), ["objective=None"]),
    row("api", api(unit=3), ["unit=3"]),
    row("api", api(folds=True), ["folds=True"]),
    row("api", api(seed=True), ["seed=True"]),
    row("api", api(seed=float("nan")), ["seed=nan"]),
    row("api", api(folds=1e9), ["folds=1000000000", "at most"]),
    row("api", lambda: magexp_calibration().export("ardupilot", "x.param", counts_nt="abc"), ["counts_nt='abc'"]),
    row("api", lambda: magexp_calibration().export("ardupilot", "x.param", max_rotation_deg=-1),
        ["max_rotation_deg=-1"]),
    row("api", load("random.bin"), ["random.bin", "byte 0"]),
    row("api", load("flipped.bin"), ["flipped.bin", "damaged"]),
    # ---- issue 41, sweeps and Hydra's switches and keys: every sweep spelling counted before it expands (the
    #      command line, hydra.sweeper.params, config-group sweeps, nested values); every hydra.* key and Hydra
    #      switch does what Hydra documents or is refused in one line; reproduce's options checked
    *[row("sweep", ["-m", params, *rest], words) for params, rest, words in [
        ('hydra.sweeper.params={seed: "range(0,300000)"}', [], ["seed=range(0,300000)", "MAGEXP_MAX_RUNS"]),
        ('hydra.sweeper.params={seed: "range(1000000000)"}', [], ["seed=range(1000000000)", "MAGEXP_MAX_RUNS"]),
        ('hydra.sweeper.params={seed: "range(300000)"}', ["scenario.noise=1"], ["seed=range(300000)", "runs"]),
        ('hydra.sweeper.params={scenario.noise: "range(1000)"}', ["seed=range(1000)"], ["range(1000)", "runs"]),
        ("hydra.sweeper.params={scenario.name: ${oc.env:HOME}}", [], ["hydra.sweeper.params", "interpolations"]),
        ("hydra.sweeper.params={seed: '${oc.env:HOME}'}", [], ["hydra.sweeper.params", "interpolations"]),
        ('hydra.sweeper.params={hydra.launcher.jobs: "1,2"}', [], ["hydra.sweeper.params.hydra.launcher.jobs",
                                                                   "hydra.* setting"]),
        ("hydra.sweeper.params={seed: [1,2]}", [], ["hydra.sweeper.params.seed", "string"]),
        ("hydra.sweeper.params={seed: null}", [], ["hydra.sweeper.params.seed", "string"]),
        ("hydra.sweeper.params={scenario: {noise: 1}}", [], ["hydra.sweeper.params.scenario", "string"]),
        ('hydra.sweeper.params={scenario.noise: "2,-1"}', [], ["scenario.noise=-1"]),
        ('hydra.sweeper.params={scenario.nosie: "1,2"}', [], ["'nosie'"]),
        ('hydra.sweeper.params={seed: "0,-4"}', [], ["seed=-4"]),
        ('hydra.sweeper.params={seed: "interval(0,1)"}', [], ["interval(0,1)", "range()"]),
        ('hydra.sweeper.params={estimator: "glob(zzz*)"}', [], ["glob(zzz*)", "no job"]),
        ('hydra.sweeper.params={estimator: "lm,bogus"}', [], ["'bogus'"]),
        ('hydra.sweeper.params={estimator._target_: "os.system"}', [], ["_target_"]),
        ('hydra.sweeper.params={seed: "1,2"}', ["hydra.sweeper.params=null"], ["hydra.sweeper.params given twice"]),
    ]],
    row("sweep", ["-m", "estimator=lm,ls,ipso", "seed=range(100000)"], ["seed=range(100000)", "MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "estimator=glob(*)", "seed=range(20000)"], ["seed=range(20000)", "MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "estimator=glob(*)", "scenario=glob(*)", "seed=range(1000)"], ["MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "seed=range(0,1,1e-9)"], ["seed=range(0,1,1e-9)", "MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "seed=shuffle(range(300000))"], ["shuffle(range(300000))", "MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "seed=sort(range(300000),reverse=true)"], ["MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "seed=tag(a,range(300000))"], ["MAGEXP_MAX_RUNS"]),
    row("sweep", ["-m", "seed=range(5),7"], ["seed=range(5),7", "one range()"]),
    row("sweep", ["-m", "seed=range(3),range(2)"], ["seed=range(3),range(2)", "one range()"]),
    row("sweep", ["-m", "scenario.noise=1,2", "seed=range(2),5"], ["seed=range(2),5"]),
    *[row("sweep", ["-m", *MOCKUP, "seed=1,2", f"hydra.sweeper.max_batch_size={v}"],
          [f"hydra.sweeper.max_batch_size={w}", ">= 1"]) for v, w in [("-1", "-1"), ("0", "0"), ("abc", "'abc'"),
                                                                      ("true", "True"), ("1.5", "1.5")]],
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.launcher=null"], ["hydra.launcher=", "hydra/launcher=<name>"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.launcher=5"], ["hydra.launcher=5", "hydra/launcher=<name>"]),
    *[row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra/launcher=joblib", f"hydra.launcher.{k}={v}"], words)
      for k, v, words in [("n_jobs", "100000", ["hydra.launcher.n_jobs=100000", "cores"]),
                          ("n_jobs", "0", ["hydra.launcher.n_jobs=0", "-1 (all cores)"]),
                          ("n_jobs", "-100000", ["hydra.launcher.n_jobs=-100000", "cores"]),
                          ("n_jobs", "abc", ["hydra.launcher.n_jobs", "abc"]),
                          ("verbose", "-1", ["hydra.launcher.verbose=-1", ">= 0"]),
                          ("timeout", "-1", ["hydra.launcher.timeout=-1", "> 0"]),
                          ("timeout", "nan", ["hydra.launcher.timeout=nan", "> 0"]),
                          ("batch_size", "0", ["hydra.launcher.batch_size='0'", "auto"]),
                          ("batch_size", "x", ["hydra.launcher.batch_size='x'", "auto"]),
                          ("temp_folder", "/tmp", ["hydra.launcher.temp_folder='/tmp'", "n_jobs"]),
                          ("backend", "threading", ["hydra.launcher.backend='threading'", "n_jobs"]),
                          ("pre_dispatch", "all", ["hydra.launcher.pre_dispatch='all'", "n_jobs"]),
                          ("mmap_mode", "w+", ["hydra.launcher.mmap_mode='w+'", "n_jobs"]),
                          ("nosuch", "1", ["hydra.launcher.nosuch"])]],
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra/launcher=basic", "hydra.launcher.foo=1"], ["hydra.launcher.foo"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra/sweeper=nope"], ["hydra/sweeper/nope"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra/job_logging=nope"], ["hydra/job_logging/nope"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra/hydra_logging=nope"], ["hydra/hydra_logging/nope"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.job.chdir=true"], ["hydra.job.chdir=true", "absolute paths"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.job.chdir=abc"], ["hydra.job.chdir=abc"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.job.name=${oc.env:HOME}"], ["hydra.job.name", "interpolations"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.verbose=${oc.env:HOME}"], ["hydra.verbose", "interpolations"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.job.config.override_dirname.kv_sep=${oc.env:HOME}"],
        ["override_dirname.kv_sep", "interpolations"]),
    row("sweep", ["-m", *MOCKUP, "seed=1,2", "hydra.job.config.override_dirname.exclude_keys=1"],
        ["exclude_keys=1"]),
    *[row("sweep", ["-m", *MOCKUP, "seed=1,2", f"hydra.sweep.subdir={v}"], ["hydra.sweep.subdir", "${hydra.job.num}"])
      for v in ["${oc.env:HOME}", "${hydra:runtime.cwd}", "job_${now:%H}", "${hydra.job.num}_${oc.env:USER}",
                "${hydra.run.dir}"]],
    *[row("sweep", ["-m", *MOCKUP, "seed=1,2", a, b], [f"{key} given twice"]) for key, a, b in [
        ("hydra.sweep.dir", "hydra.sweep.dir=a_folder", "hydra.sweep.dir=results/x"),
        ("hydra.sweep.dir", "hydra.sweep.dir=s1", "++hydra.sweep.dir=s2"),
        ("hydra.sweep.subdir", "hydra.sweep.subdir=${hydra.job.num}", "hydra.sweep.subdir=x${hydra.job.num}"),
        ("hydra.launcher.jobs", "hydra.launcher.jobs=1", "hydra.launcher.jobs=2"),
        ("hydra/launcher", "hydra/launcher=basic", "hydra/launcher=magexp"),
        ("hydra.sweeper.max_batch_size", "hydra.sweeper.max_batch_size=1", "hydra.sweeper.max_batch_size=2")]],
    row("run", ["hydra.run.dir=r1", "hydra.run.dir=r2"], ["hydra.run.dir given twice"]),
    *[row("sweep", ["-m", *MOCKUP, "seed=1,2", ov], [ov.partition("=")[0].lstrip("+"), "not allowed"]) for ov in [
        "hydra.output_subdir=null", "hydra.searchpath=[pkg://os]", "hydra.mode=RUN", "+hydra.job.env_set.X=1",
        "hydra.job.env_copy=[HOME]", "hydra.runtime.cwd=/", "hydra.help.template=x", "hydra.hydra_help.template=x",
        "hydra.job_logging.root.level=DEBUG", "hydra.hydra_logging.root.level=DEBUG", "hydra.overrides.task=[]",
        "hydra.job.id=1", "hydra.job.num=1", "hydra.sweeper.foo=1", "hydra.callbacks=null", "hydra.run=null",
        "hydra.sweep=null", "hydra.job=null", "hydra.sweeper.params.seed=1,2", "hydra.run.foo=1",
        "hydra.launcher_x=1"]],
    *[row("run", args, words) for args, words in [
        (["--package", "foo"], ["--package 'foo'", "--cfg"]),
        (["-p", "scenario"], ["-p 'scenario'", "--cfg"]),
        (["--cfg", "job", "--package", "foo"], ["--package 'foo'", "scenario, estimator"]),
        (["--cfg", "job", "--package", "seed"], ["--package 'seed'", "scenario"]),
        (["--cfg", "job", "--package", "objective"], ["--package 'objective'"]),
        (["--cfg", "job", "--package", ""], ["--package ''"]),
        (["--cfg", "job", "--package", "scenario.nosuch"], ["'scenario.nosuch'"]),
        (["--cfg", "hydra", "--package", "scenario"], ["--package 'scenario'", "hydra"]),
        (["--cfg", "all", "-p", "nosuch"], ["'nosuch'", "scenario"]),
        (["--resolve"], ["--resolve", "--cfg"]),
        (["--resolve", "estimator=lm"], ["--resolve", "--cfg"]),
        (["-m", "--cfg", "job"], ["--multirun and --cfg", "one of"]),
        (["--cfg", "job", "--info"], ["--cfg and --info"]),
        (["-sc", "install=bash", "-m"], ["--multirun", "--shell-completion"]),
        (["-r", "-m", "seed=1,2"], ["--run and --multirun"]),
        (["--run", "--info", "plugins"], ["--run and --info"]),
        (["-sc", "foo"], ["-sc 'foo'", "install"]),
        (["-sc", "install=tcsh"], ["'install=tcsh'", "bash"]),
        (["--shell-completion", "install"], ["'install'", "bash"]),
        (["-sc", "query=bash"], ["'query=bash'", "COMP_LINE"]),
        (["--shell-completion"], ["--shell-completion needs a value"]),
        (["--info=zzz"], ["--info 'zzz'", "searchpath"]),
        (["--info", "seed=1"], ["--info 'seed=1'", "searchpath"]),
        (["-i", "zz"], ["'zz'", "searchpath"]),
        (["-i", "-m", "seed=1,2"], ["--info and --multirun"]),
        (["--cfg=foo"], ["--cfg 'foo'", "job"]),
        (["--config-name=nosuch"], ["'nosuch'"]),
        (["--config-dir=/tmp"], ["--config-dir", "conf/"]),
        (["--experimental-rerun=evil.pickle"], ["--experimental-rerun", "unpickles"]),
    ]],
    row("reproduce", ["--limits", "zzz"], ["'zzz'", "ding2024"]),
    row("reproduce", ["zzz", "--limits"], ["'zzz'", "ding2024"]),
    row("reproduce", ["ding2024", "--limits", "--out", "x"], ["--limits", "--out"]),
    row("reproduce", ["--limits", "--seeds", "2"], ["--limits", "--seeds"]),
    row("reproduce", ["--limits", "--only", "ding2024_fig3"], ["--limits", "--only"]),
    row("reproduce", ["all", "--limits", "--redraw"], ["--limits", "--redraw"]),
    row("reproduce", ["--limits", "--jobs", "2"], ["--limits", "--jobs"]),
    row("reproduce", ["ding2024", "--only", "ding2024_fig3", "--out", "${oc.env:HOME}"],
        ["--out='${oc.env:HOME}'", "interpolations"]),
    row("reproduce", ["ding2024", "--only", "ding2024_fig3", "--out", "x/${hydra:runtime.cwd}"], ["interpolations"]),
    row("reproduce", ["ding2024", "--only", "ding2024_fig3", "--out", "a\nb"], ["control characters"]),
    row("reproduce", ["ding2024", "--only", "ding2024_fig3", "--tiny", "--out", "\t"], ["--out='\\t'"]),
    # ---- issue 41, files and verify (items 1 and 4): one gate for every file read (a device, a FIFO, a /proc
    # file, a 10 MB line, each through every path that reads a file); every MAGEXP_MAX_* checked by every command,
    # an empty value included; verify reads only results folders and reproduces only where it is told
    *[row("calibrate", [f"data.path={path}", "data.unit=uT"], [f"data.path='{path}'", allowed])
      for path, allowed in (("one_line.txt", "MAGEXP_MAX_LINE"), ("/proc/self/status", "size is unknown"))],
    *[row("run", [*MOCKUP, f"scenario.path={path}"], [f"scenario.path='{path}'", allowed])
      for path, allowed in (("one_line.txt", "MAGEXP_MAX_LINE"), ("/proc/self/status", "size is unknown"),
                            ("/dev/zero", "character device"))],
    row("run", ["estimator=lm", "scenario=real_fxos8700", "scenario.file=/proc/self/status"],
        ["scenario.file='/proc/self/status'", "size is unknown"]),
    row("run", ["scenario=real_hmc5883l_full_sphere", "estimator=lm", "scenario.rest_file=/proc/self/status"],
        ["scenario.rest_file=", "size is unknown"]),
    *[row("api", api(readings=path), ["readings=", allowed])
      for path, allowed in (("one_line.txt", "MAGEXP_MAX_LINE"), ("/proc/self/status", "size is unknown"),
                            ("/dev/zero", "character device"))],
    *[row("api", lambda path=path: __import__("magexp").Calibration.load(path), ["path=", allowed])
      for path, allowed in (("one_line.txt", "MAGEXP_MAX_LINE"), ("/proc/self/status", "size is unknown"),
                            ("/dev/zero", "character device"), ("a_folder", "a folder"))],
    *[row(entry, args, [f"{name}={value!r}", "number > 0"], patch=[
        ("magexp.core.limits.os", __import__("types").SimpleNamespace(environ={name: value}))])
      for name in ("MAGEXP_MAX_RUN_MEMORY", "MAGEXP_MAX_RUN_WORK", "MAGEXP_MAX_RUNS", "MAGEXP_MAX_WORK",
                   "MAGEXP_MAX_READINGS", "MAGEXP_MAX_FILE", "MAGEXP_MAX_LINE")
      for value, (entry, args) in zip(("", "-5", "abc", "0", "1e999", " ", "nan"), (
          ("run", ["seed=1"]), ("calibrate", ["data.path=good.csv"]), ("sweep", ["-m", "seed=1,2"]),
          ("reproduce", ["yuan2018"]), ("api", api()), ("run", ["verify", "--against", "a_folder"]),
          ("run", ["calibrate", "data.path=plain.txt", "data.unit=uT"])))],
    row("api", api(), ["MAGEXP_MAX_READINGS=''"],
        patch=[("magexp.core.limits.os", __import__("types").SimpleNamespace(environ={"MAGEXP_MAX_READINGS": ""}))]),
    *[row("run", ["verify", option, folder], [f"{option} '{folder}'", allowed])
      for option in ("--committed", "--against")
      for folder, allowed in (("/etc", "not a results folder"), ("a_folder", "not a results folder"),
                              ("a_file", "not a folder"), ("pipe.fifo", "not a folder"), ("/dev/zero", "not a folder"))],
    row("run", ["verify", "--into", "taken"], ["--into 'taken'", "no reproduction's", "new or empty"]),
    row("run", ["verify", "--into", "/etc"], ["--into '/etc'", "no reproduction's"]),
    row("run", ["verify", "--into", "results/x"], ["--into", "results"]),
    row("run", ["verify", "--against", R(), "--into", "a_folder"], ["--into 'a_folder'", "with --against"]),
    # ---- issue 41, every key validated by its schema: duplicates, text for numbers, integer bounds, empty names,
    # subnormal numbers, format names, axis maps, a field model's date without a place, list shapes, a zero field
    row("run", ["scenario.noise=1", "scenario.noise=2"], ["scenario.noise given twice"]),
    row("run", ["seed=1", "seed=2"], ["seed given twice"]),
    row("run", ["hydra.run.dir=a", "hydra.run.dir=b"], ["hydra.run.dir given twice"]),
    row("sweep", ["-m", "scenario.noise=1,2", "scenario.noise=3"], ["scenario.noise given twice"]),
    row("calibrate", ["data.path=good.csv", "data.unit=uT", "data.unit=nT"], ["data.unit given twice"]),
    row("run", ["scenario.noise='1'"], ["scenario.noise='1'", "a number", "not a text"]),
    row("run", ["estimator.n_particles='30'"], ["estimator.n_particles='30'", "an integer"]),
    row("run", ["seed=99999999999999999999"], ["seed=99999999999999999999", "1e+15"]),
    row("run", ["seed=1000000000000001"], ["seed=1000000000000001", "1e+15"]),  # the API's bound too (MAX_SEED)
    row("sweep", ["-m", "seed=1,99999999999999999999"], ["seed=99999999999999999999", "1e+15"]),
    row("run", ["objective="], ["objective=''", "give a value"]),
    row("run", ["estimator.name="], ["estimator.name=''", "give a value"]),
    row("run", ["estimator=pso", "estimator.velocity_limit=1e-320"], ["estimator.velocity_limit=1e-320", "1e-100"]),
    row("run", ["estimator=cmaes", "estimator.sigma0=1e-320"], ["estimator.sigma0=1e-320", "1e-100"]),
    row("run", ["estimator=cmaes", "estimator.sigma0=-1e-320"], ["estimator.sigma0=-1e-320", "1e-100"]),
    row("run", ["scenario=real_fxos8700", "estimator=lm", "scenario.window=[0,0,0]"], ["scenario.window=", "start, end"]),
    row("run", ["scenario=real_fxos8700", "estimator=lm", "scenario.window=[0,10]"], ["scenario.window=", "no reading times"]),
    row("run", ["scenario=real_hmc5883l_full_sphere", "estimator=lm", "scenario.window=[5,3]"], ["scenario.window=", "start < end"]),
    row("run", ["scenario=yan2022_sim", "estimator=lm", "scenario.field=[0,0,0]"], ["scenario.field=", "not be zero"]),
    row("run", ["scenario=yan2022_sim", "estimator=lm", "scenario.field=[1,2]"], ["scenario.field=[1,2]", "3 numbers"]),
    row("run", ["scenario.search.offset=[1,2,3]"], ["scenario.search.offset=[1,2,3]", "2 numbers"]),
    row("calibrate", ["data.path=good.csv", "data.format="], ["data.format=''", "give a value"]),
    row("calibrate", ["data.path=good.csv", "data.format=zzz"], ["data.format='zzz'", "magexp-v1"]),
    row("calibrate", ["data.path=good.csv", "data.gyro_axes=zz"], ["data.gyro_axes='zz'", "x, y, z"]),
    row("calibrate", ["data.path=good.csv", "data.unit=uT", "field.date=2020-01-01"], ["field.date='2020-01-01'",
                                                                                        "field.latitude"]),
    row("calibrate", ["data.path=good.csv", "data.unit=uT", "field.longitude=10"], ["field.longitude=10", "place"]),
    row("calibrate", ["data.path=good.csv", "data.format=rosbag"], ["data.format='rosbag'", ".mcap"]),
    row("calibrate", ["data.path=[a,b]"], ["data.path=['a', 'b']", "text"]),
    row("calibrate", ["data.path=good.csv", "seed=99999999999999999999"], ["seed=99999999999999999999", "1e+15"]),
    row("calibrate", ["data.path=good.csv", "objective="], ["objective=''"]),
    row("calibrate", ["data.path=good.csv", "gate.scale_range=[1,2,3]"], ["gate.scale_range=[1,2,3]", "2 numbers"]),
    row("calibrate", ["data.path=good.csv", "estimator=cmaes", "estimator.sigma0=1e-320"], ["estimator.sigma0=1e-320"]),
]


# ---- issue 41, the API as strict as the command line (item 6): every key of a saved calibration.json corrupted
#      in each way (missing, a wrong type, NaN, out of range, an extra key), files Calibration.load must not parse
#      unbounded, every argument of magexp.calibrate, apply, save and export given a wrong type or value, and a
#      user's estimator that fails: each one MagexpError line

#: the folder of the crafted calibration files (outside the watched tree: writing them is the test's, not the call's)
_CRAFTED = tempfile.TemporaryDirectory(prefix="magexp-crafted-")


@functools.cache
def saved_calibration() -> str:
    """The JSON text of a good calibration (``magexp_calibration()``'s, as ``Calibration.save`` writes it)."""
    from magexp.calibration.write import parameters

    return json.dumps(parameters(magexp_calibration()))


def crafted(content, name: str = "calibration.json") -> str:
    """A file of ``content`` (text, or a dict dumped as JSON) in :data:`_CRAFTED`, under a name of its own."""
    text = content if isinstance(content, str) else json.dumps(content)
    path = Path(tempfile.mkdtemp(dir=_CRAFTED.name)) / name
    path.write_text(text)
    return str(path)


def load_edited(edit):
    """A call of ``Calibration.load`` on a good calibration.json changed by ``edit(data)`` (in place)."""
    import magexp

    def call():
        data = json.loads(saved_calibration())
        edit(data)
        return magexp.Calibration.load(crafted(data))
    return call


def _set(*keys, value=None, delete=False):
    """An edit setting (or deleting) ``data[k1][k2]...``."""
    def edit(data):
        node = data
        for key in keys[:-1]:
            node = node[key]
        if delete:
            del node[keys[-1]]
        else:
            node[keys[-1]] = copy.deepcopy(value)
    return edit


def _wrong_type(value):
    """A JSON value of another type than ``value``."""
    return [1] if isinstance(value, dict) else "abc" if isinstance(value, list) else 3 if isinstance(value, str) \
        else {"x": 1} if value is None else "3"


#: each top-level key of calibration.json given a value out of its range (None: its schema has no range)
OUT_OF_RANGE = {"format": "magexp-calibration v9", "model": "B = W r", "recording": "", "n_readings": 0,
                "unit": "furlong", "field_unit": "abc", "estimator": "", "objective": "bogus", "seed": -1,
                "W": [[1e300, 0, 0], [0, 1, 0], [0, 0, 1]], "W_form": "two\nlines", "offset": [1e300, 0, 0],
                "reference": {"total": -1}, "search": "", "metrics": {"spread_before": -1},
                "quality": {"model": "bogus"}, "fit": {"nit": -1}, "config": None, "provenance": None}
#: the nested keys the summary reads, each corrupted too: {parent: keys}
NESTED = {"reference": ("total", "per_reading", "source", "estimated", "how"),
          "fit": ("fun", "nit", "nfev", "success", "message"),
          "metrics": ("mean_before", "spread_before", "rms_before", "mean_after", "spread_after", "rms_after",
                      "coverage_cells", "coverage_lambda_min"),
          "quality": ("W_standard_errors", "offset_standard_errors", "condition_number", "undetermined",
                      "weakest_combinations", "model")}


def corrupted_rows() -> list:
    """Every key of a saved calibration.json missing, of a wrong type, NaN and out of range; the nested keys the
    summary reads missing, of a wrong type and NaN; an extra key at the top and in the fixed records."""
    rows = []
    for key, bad in OUT_OF_RANGE.items():
        said = "format" if key == "format" else f"{key}="
        rows += [row("api", load_edited(_set(key, delete=True)), ["format None"] if key == "format" else
                     [f"'{key}'", "missing"]),
                 row("api", load_edited(lambda data, key=key: data.__setitem__(key, _wrong_type(data[key]))),
                     [key, "not allowed"]),
                 row("api", load_edited(_set(key, value=float("nan"))), [said, "nan"])]
        if bad is not None:
            edit = (lambda data, key=key, bad=bad: data[key].update(bad)) if isinstance(bad, dict) else \
                _set(key, value=bad)
            rows.append(row("api", load_edited(edit), [key, "not allowed"]))
    for parent, keys in NESTED.items():
        for key in keys:
            rows += [row("api", load_edited(_set(parent, key, delete=True)), [f"{parent}=", key]),
                     row("api", load_edited(lambda data, p=parent, k=key: data[p].__setitem__(k, _wrong_type(data[p][k]))),
                         [f"{parent}=", key]),
                     row("api", load_edited(_set(parent, key, value=float("nan"))), [f"{parent}=", key])]
    rows += [row("api", load_edited(_set("extra", value=1)), ["'extra'", "not allowed"]),
             row("api", load_edited(_set("reference", "extra", value=1)), ["reference=", "'extra'"]),
             row("api", load_edited(_set("fit", "extra", value=1)), ["fit=", "'extra'"])]
    return rows


class RaisingEstimator:
    """A user's estimator whose fit raises ``error``."""

    name = "mine"

    def __init__(self, error):
        self.error = error

    def fit(self, problem, rng=None):
        raise self.error


class ReturningEstimator:
    """A user's estimator whose fit returns ``result(problem)`` (no ``name``: its class names it)."""

    def __init__(self, result):
        self.result = result

    def fit(self, problem, rng=None):
        return self.result(problem)


def fit_result(x=None, **fields):
    """A ``result(problem)`` building a FitResult of ``x`` (None: the problem's zero vector + 1) and ``fields``."""
    from magexp.estimators.result import FitResult

    def result(problem):
        values = {"fun": 0.0, "nit": 1, "nfev": 1, "history": np.zeros(1), "history_nfev": np.zeros(1), **fields}
        return FitResult(x=np.ones(problem.n_params) if x is None else x, **values)
    return result


def _cal_call(method, *args, **kwargs):
    """A call of ``magexp_calibration().<method>(*args, **kwargs)``."""
    return lambda: getattr(magexp_calibration(), method)(*args, **kwargs)


def _symlink_elsewhere() -> str:
    """A symbolic link (in :data:`_CRAFTED`) to a file elsewhere (``/etc/hostname``)."""
    link = Path(tempfile.mkdtemp(dir=_CRAFTED.name)) / "calibration.json"
    link.symlink_to("/etc/hostname")
    return str(link)


def _sparse(size: int) -> str:
    """A sparse file of ``size`` bytes in :data:`_CRAFTED` (none of them written)."""
    path = Path(crafted(""))
    os.truncate(path, size)
    return str(path)


def _simulate(n, seed):
    """``magexp.calibration.simulate.simulate(n, seed)``."""
    from magexp.calibration.simulate import simulate

    return simulate(n, seed)


_LOAD = lambda path: lambda: __import__("magexp").Calibration.load(path() if callable(path) else path)  # noqa: E731
_GOOD_W = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]

TABLE += corrupted_rows() + [
    # ---- W and the offset: invertible, well-conditioned, 3 x 3 and 3 finite numbers
    row("api", load_edited(_set("W", value=[[0] * 3] * 3)), ["W=", "invertible", "condition number"]),
    row("api", load_edited(_set("W", value=[[1, 0, 0], [0, 1, 0], [0, 0, 0]])), ["W=", "invertible"]),
    row("api", load_edited(_set("W", value=[[1, 0, 0], [0, 1, 0], [0, 0, 1e-9]])), ["W=", "condition number", "1e+06"]),
    row("api", load_edited(_set("W", value=[[1, 2, 3], [2, 4, 6], [1, 1, 1]])), ["W=", "invertible"]),
    row("api", load_edited(_set("W", value=[[1, 0, 0], [0, 1, 0]])), ["W=", "3 x 3"]),
    row("api", load_edited(_set("W", value=[["1", 0, 0], [0, 1, 0], [0, 0, 1]])), ["W=", "3 x 3"]),
    row("api", load_edited(_set("W", value=[[True, 0, 0], [0, 1, 0], [0, 0, 1]])), ["W=", "3 x 3"]),
    row("api", load_edited(_set("W", value=[[float("inf"), 0, 0], [0, 1, 0], [0, 0, 1]])), ["W=", "finite"]),
    row("api", load_edited(_set("W", value=[[[1], 0, 0], [0, 1, 0], [0, 0, 1]])), ["W=", "3 x 3"]),
    row("api", load_edited(_set("W", value=_GOOD_W * 2)), ["W=", "3 x 3"]),
    row("api", load_edited(_set("offset", value=[0, 0])), ["offset=", "3 finite"]),
    row("api", load_edited(_set("offset", value=[0, 0, float("-inf")])), ["offset=", "3 finite"]),
    row("api", load_edited(_set("offset", value=[0, 0, None])), ["offset=", "3 finite"]),
    row("api", load_edited(_set("seed", value=2 ** 64)), ["seed=", "integer in"]),
    row("api", load_edited(_set("seed", value=1.5)), ["seed=1.5", "integer"]),
    row("api", load_edited(_set("n_readings", value=True)), ["n_readings=True", "integer"]),
    row("api", load_edited(_set("unit", value="")), ["unit=''", "uT"]),
    row("api", load_edited(_set("quality", "heading", value={"tilt_deg": 30})), ["quality or metrics record"]),
    row("api", load_edited(_set("search", value={"diag": [0, 1]})), ["search=", "diag, offdiag, offset"]),
    row("api", load_edited(_set("provenance", value={"magexp_version": 1})), ["provenance=", "magexp_version"]),
    row("api", load_edited(_set("quality", "weakest_combinations", value=[])), ["weakest_combinations", "non-empty"]),
    row("api", load_edited(_set("reference", "unit", value="furlong")), ["reference=", "unit"]),
    row("api", load_edited(_set("files", value=[])), ["files=", "object"]),
    # ---- files Calibration.load reads within bounds: one line, never a traceback, a hang or memory spent
    row("api", _LOAD(lambda: crafted("[\n" * 100_000 + "]\n" * 100_000)), ["nested deeper than 64"]),
    row("api", _LOAD(lambda: crafted('{"format": "magexp-calibration v3", "seed": ' + "9" * 60_000 + "}")),
        ["a number of 60000 characters", "at most 64"]),
    row("api", _LOAD(lambda: crafted("[" * 100_000 + "]" * 100_000)), ["path=", "line", "MAGEXP_MAX_LINE"]),
    row("api", _LOAD(lambda: crafted('{"seed": ' + "9" * 100_000 + "}")), ["path=", "line", "MAGEXP_MAX_LINE"]),
    row("api", _LOAD(lambda: crafted(saved_calibration().replace('"W": [[', '"W": [[1e999, '))), ["W=", "finite"]),
    row("api", _LOAD(lambda: crafted("")), ["not a calibration.json", "JSONDecodeError"]),
    row("api", _LOAD(lambda: crafted("null")), ["format 'NoneType'", "magexp-calibration v3"]),
    row("api", _LOAD(lambda: crafted('"magexp-calibration v3"')), ["format 'str'"]),
    row("api", _LOAD(lambda: crafted('{"format": "magexp-calibration v3"}{}')), ["not a calibration.json"]),
    row("api", _LOAD(lambda: crafted("\ufeff{}")), ["not a calibration.json"]),
    row("api", _LOAD(lambda: _sparse(2 ** 30)), ["path=", "MAGEXP_MAX_RUN_MEMORY"]),
    row("api", _LOAD(lambda: _sparse(3 * 2 ** 30)), ["path=", "MAGEXP_MAX_FILE"]),
    row("api", _LOAD("/dev/zero"), ["path='/dev/zero'", "character device"]),
    row("api", _LOAD("missing.json"), ["path='missing.json'", "does not exist"]),
    row("api", _LOAD("a_folder"), ["path='a_folder'", "a folder"]),
    row("api", _LOAD(3), ["path=3", "calibration.json"]),
    row("api", _LOAD(None), ["path=None"]),
    row("api", _LOAD(""), ["path=''"]),
    row("api", _LOAD("binary.csv"), ["binary.csv", "UnicodeDecodeError"]),
    row("api", _LOAD("secret.txt"), ["secret.txt", "not a calibration.json"]),
    # ---- apply: finite readings of shape (N, 3) or (3,)
    row("api", _cal_call("apply", np.full((4, 3), np.nan)), ["row 0", "finite"]),
    row("api", _cal_call("apply", np.r_[np.ones((5, 3)), [[1, np.inf, 2]]]), ["row 5", "finite", "1 rows"]),
    row("api", _cal_call("apply", [1.0, float("nan"), 2.0]), ["row 0", "finite"]),
    row("api", _cal_call("apply", np.ones((2, 2, 3))), ["shape (2, 2, 3)"]),
    row("api", _cal_call("apply", np.ones(4)), ["shape (4,)"]),
    row("api", _cal_call("apply", "abc"), ["readings", "number"]),
    row("api", _cal_call("apply", None), ["readings of type NoneType"]),
    row("api", _cal_call("apply", np.ones((3, 3)) + 1j), ["complex"]),
    row("api", _cal_call("apply", {"x": 1}), ["readings of type dict"]),
    # ---- save and export: regular files in existing folders, replacing only a calibration's own regular file
    row("api", _cal_call("save", "pipe.fifo", overwrite=True), ["pipe.fifo", "a FIFO"]),
    row("api", _cal_call("save", "/dev/full", overwrite=True), ["/dev/full", "character device"]),
    row("api", _cal_call("save", "/dev/null", overwrite=True), ["/dev/null", "character device"]),
    row("api", lambda: magexp_calibration().save(_symlink_elsewhere(), overwrite=True), ["symbolic link"]),
    row("api", _cal_call("save", "a_folder", overwrite=True), ["a_folder", "a folder"]),
    row("api", _cal_call("save", "no_such_folder/calibration.json"), ["no_such_folder", "does not exist"]),
    row("api", _cal_call("save", "a_file/calibration.json"), ["a_file", "not a folder"]),
    row("api", _cal_call("save", 3), ["path=3", "a file's path"]),
    row("api", _cal_call("save", None), ["path=None"]),
    row("api", _cal_call("save", ""), ["path=''"]),
    row("api", _cal_call("save", "new.json", overwrite="yes"), ["overwrite='yes'", "True or False"]),
    row("api", _cal_call("save", "secret.txt", overwrite=True), ["secret.txt", "no calibration wrote it"]),
    row("api", _cal_call("export", "px4", "pipe.fifo", overwrite=True), ["pipe.fifo", "a FIFO"]),
    row("api", _cal_call("export", "ros", "/dev/full", overwrite=True), ["/dev/full", "character device"]),
    row("api", lambda: magexp_calibration().export("c", _symlink_elsewhere(), overwrite=True), ["symbolic link"]),
    row("api", _cal_call("export", "px4", "no_such_folder/mag.params"), ["no_such_folder", "does not exist"]),
    row("api", _cal_call("export", "px4", 3), ["export path=3", "a file's path"]),
    row("api", _cal_call("export", "px4", "x.params", overwrite=1), ["overwrite=1", "True or False"]),
    row("api", _cal_call("export", None), ["export=None", "ardupilot"]),
    row("api", _cal_call("export", "px4", "x.params", nosuch=1), ["nosuch"]),
    # ---- a user's estimator: its failure wrapped naming it, its result checked
    row("api", api(estimator=RaisingEstimator(AttributeError("no attribute 'x'"))),
        ["estimator='mine' failed", "AttributeError"]),
    row("api", api(estimator=RaisingEstimator(TypeError("bad operand"))), ["estimator='mine' failed", "TypeError"]),
    row("api", api(estimator=RaisingEstimator(RecursionError("deep"))), ["estimator='mine'", "RecursionError"]),
    row("api", api(estimator=RaisingEstimator(ZeroDivisionError("division by zero"))), ["estimator='mine'"]),
    row("api", api(estimator=RaisingEstimator(OSError("disk"))), ["estimator='mine'", "OSError"]),
    row("api", api(estimator=ReturningEstimator(lambda p: 3)), ["'ReturningEstimator'", "returned int"]),
    row("api", api(estimator=ReturningEstimator(lambda p: None)), ["returned NoneType", "FitResult"]),
    row("api", api(estimator=ReturningEstimator(fit_result(np.zeros(5)))), ["FitResult.x", "12 numbers"]),
    row("api", api(estimator=ReturningEstimator(fit_result(np.array(["a"] * 12)))), ["FitResult.x"]),
    row("api", api(estimator=ReturningEstimator(fit_result(np.full(12, np.nan))), folds=0), ["non-finite calibration"]),
    row("api", api(estimator=ReturningEstimator(fit_result(np.zeros(12))), folds=0), ["singular W"]),
    row("api", api(estimator=ReturningEstimator(fit_result(fun="x"))), ["FitResult.fun='x'"]),
    row("api", api(estimator=ReturningEstimator(fit_result(nit=-1))), ["FitResult.nit=-1", "integer >= 0"]),
    row("api", api(estimator=ReturningEstimator(fit_result(success="yes"))), ["FitResult.success='yes'"]),
    row("api", api(estimator=ReturningEstimator(fit_result(message=None))), ["FitResult.message=None"]),
    # ---- every argument of magexp.calibrate given a wrong type or value
    row("api", api(unit=""), ["unit=''", "uT"]),
    row("api", api(unit=["uT"]), ["unit=['uT']"]),
    row("api", api(estimator=None), ["estimator=None"]),
    row("api", api(estimator=""), ["estimator=''"]),
    row("api", api(estimator=["lm"]), ["estimator=['lm']"]),
    row("api", api(objective=3), ["objective=3", "scalar"]),
    row("api", api(objective=""), ["objective=''", "scalar"]),
    row("api", api(reference_total=float("nan")), ["reference_total=nan"]),
    row("api", api(reference_total=float("inf")), ["reference_total=inf"]),
    row("api", api(reference_total=0), ["reference_total=0", "> 0"]),
    row("api", api(reference_total="40"), ["reference_total='40'", "number"]),
    row("api", api(folds=None), ["folds=None", "integer >= 0"]),
    row("api", api(folds=[2]), ["folds=[2]"]),
    row("api", api(folds=float("nan")), ["folds=nan"]),
    row("api", api(seed=2 ** 64), ["seed=18446744073709551616", "1e+15"]),
    row("api", api(seed=10 ** 15 + 1), ["seed=1000000000000001", "1e+15"]),  # the command line's bound (MAX_SEED)
    row("api", api(seed="1"), ["seed='1'"]),
    row("api", api(seed=None), ["seed=None"]),
    row("api", api(seed=float("inf")), ["seed=inf"]),
    row("api", api(checks=1), ["checks=1"]),
    row("api", api(model=3), ["model=3", "full"]),
    row("api", api(model=""), ["model=''", "full"]),
    row("api", api(accept=None), ["accept=None"]),
    row("api", api(accept="true"), ["accept='true'"]),
    row("api", api(gate=[1]), ["gate=[1]", "mapping"]),
    row("api", api(gate={"max_rms_mG": "abc"}), ["gate.max_rms_mG='abc'"]),
    row("api", api(gate={"max_rms_mG": float("nan")}), ["gate.max_rms_mG=nan"]),
    row("api", api(gate={1: 2}), ["gate.1=2"]),
    row("api", api(auto_margin=float("nan")), ["auto_margin=nan"]),
    row("api", api(auto_margin=float("inf")), ["auto_margin=inf"]),
    row("api", api(auto_margin=2), ["auto_margin=2", "[0, 1)"]),
    row("api", api(auto_margin=None), ["auto_margin=None"]),
    row("api", api(compiled="yes"), ["compiled='yes'"]),
    row("api", api(compiled=1), ["compiled=1"]),
    row("api", api(estimator="lm", max_nfev=None), ["max_nfev=None"]),
    row("api", api(estimator="lm", tol=[1]), ["tol=[1]"]),
    row("api", api(estimator="ellipsoid", foo=1), ["foo=1"]),
    row("api", api(estimator="lm", name="ipso"), ["name='ipso'", "estimator="]),
    row("api", api(estimator="lm", _target_="os.system"), ["_target_='os.system'"]),
    row("api", api(readings=np.ones((2, 60, 3))), ["shape (2, 60, 3)"]),
    row("api", api(readings=np.zeros((0, 3))), ["0 readings", "at least 12"]),
    row("api", api(readings=5), ["shape ()"]),
    row("api", api(readings=""), ["readings=''", "recording's path"]),
    row("api", api(readings="/dev/null"), ["readings='/dev/null'", "character device"]),
    row("api", api(readings="a_folder"), ["a_folder", "directory"]),
    row("api", api(readings=np.r_[SPHERE, [[np.inf, 0, 0]]]), ["NaN or infinite"]),
    row("api", api(readings=(x for x in SPHERE)), ["readings"]),
    row("api", api(readings=["1,2,3"] * 60), ["readings", "number"]),
    # ---- the simulated recording of the docs (magexp.calibration.simulate.simulate)
    row("api", lambda: _simulate(-1, 0), ["n=-1", "integer >= 12"]),
    row("api", lambda: _simulate("a", 0), ["n='a'"]),
    row("api", lambda: _simulate(None, 0), ["n=None"]),
    row("api", lambda: _simulate(2.5, 0), ["n=2.5"]),
    row("api", lambda: _simulate(10 ** 12, 0), ["n=1000000000000", "MAGEXP_MAX_READINGS"]),
    row("api", lambda: _simulate(12, -1), ["seed=-1"]),
    row("api", lambda: _simulate(12, 2 ** 64), ["seed=18446744073709551616", "1e+15"]),
    row("api", lambda: _simulate(12, "x"), ["seed='x'"]),
]


# ---- generated from conf/: every numeric key of every estimator and scenario config (each class's key
#      once) given a wrong type, NaN, infinity, a negative number and, where its meaning excludes it, zero;
#      through the command line and, for the estimators that calibrate, through the API

#: keys whose line names them by their last part: the search box, shared by every scenario, names its own arguments
PART_NAMED = {"scenario.matrix_bound": "matrix_bound"}
#: keys whose negative values have a meaning (angles)
NEGATIVE_ALLOWED = {"scenario.field.inclination", "scenario.field.declination"}
#: keys whose zero has a meaning: a default (cma's population, the filter's horizon: its n_steps), none (no noise, drift, process noise, burn-in,
#: folds), a tolerance met only at the budget's end, a prior or coefficient that switches its term off
ZERO_ALLOWED = {
    "estimator.popsize@magexp.estimators.cmaes.CMAES", "estimator.recombination", "estimator.tol@magexp.estimators.de.",
    "estimator.tol@magexp.estimators.twostep.", "estimator.gtol", "estimator.p0_s", "estimator.p0_b", "estimator.q_s",
    "estimator.q_b", "estimator.p0", "estimator.q", "estimator.agree_k", "estimator.agree_bp", "estimator.horizon",
    "estimator.init.burn_in",
    "estimator.velocity.", "scenario.folds", "scenario.heldout_fold", "scenario.noise", "scenario.angle_noise_deg",
    "scenario.gyro.drift_deg_h", "scenario.gyro.noise_deg_s", "scenario.field.inclination",
    "scenario.field.declination", "scenario.errors.", "scenario.angle_noise",
}


def zero_allowed(key: str, target: str) -> bool:
    """Whether ``key`` of a config whose ``_target_`` is ``target`` takes 0 (:data:`ZERO_ALLOWED`:
    ``key``, a prefix of it ending in ``.``, or ``key@target-prefix``)."""
    return any(key == z or (z.endswith(".") and key.startswith(z))
               or ("@" in z and key == z.partition("@")[0] and target.startswith(z.partition("@")[2]))
               for z in ZERO_ALLOWED)


def numeric_keys(node: dict, prefix: str):
    """``(key, value)`` of every number (not a bool) under ``node``, a composed config's group."""
    for k, v in node.items():
        if isinstance(v, dict):
            yield from numeric_keys(v, f"{prefix}{k}.")
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            yield f"{prefix}{k}", v


def bad_values(key: str, target: str) -> list[tuple[str, str]]:
    """``(typed, shown)``: the values of ``key`` refused, as typed and as the line shows them."""
    out = [("abc", "abc"), ("nan", "nan"), ("inf", "inf")]
    out += [] if key in NEGATIVE_ALLOWED else [("-1", "-1")]
    return out + ([] if zero_allowed(key, target) else [("0", "0")])


def _composed_pair(scenario: str, estimator: str) -> dict:
    """``{"scenario": ..., "estimator": ...}``: the two groups composed together, or each alone where the pair is refused."""
    try:
        cfg = compose_config([f"scenario={scenario}", f"estimator={estimator}"])
    except MagexpError:
        cfg = {"scenario": compose_config([f"scenario={scenario}", "estimator=lm"]).scenario,
               "estimator": compose_config([f"estimator={estimator}"]).estimator}
    return {group: OmegaConf.to_container(cfg[group], resolve=True) for group in ("scenario", "estimator")}


@functools.cache
def composed_groups() -> dict:
    """``{(group, name): its composed config}`` of every scenario and estimator, a scenario and an estimator per
    compose (each compose is ~0.2 s of every test process's collection: 22 instead of 40)."""
    scenarios, estimators = options("scenario"), options("estimator")
    out = {}
    for i in range(max(len(scenarios), len(estimators))):
        scenario, estimator = scenarios[i % len(scenarios)], estimators[i % len(estimators)]
        pair = _composed_pair(scenario, estimator)
        out[("scenario", scenario)], out[("estimator", estimator)] = pair["scenario"], pair["estimator"]
    return out


def generated_rows() -> list:
    """The table's rows generated from ``conf/`` (see above)."""
    rows, seen = [], set()
    for group, others in (("estimator", []), ("scenario", ["estimator=lm"])):
        for name in options(group):
            node = composed_groups()[(group, name)]
            for key, value in numeric_keys(node, f"{group}."):
                target = str(node.get("_target_"))
                if (target, key) in seen:
                    continue
                seen.add((target, key))
                for typed, shown in bad_values(key, target):
                    rows.append(row("run", [f"{group}={name}", *others, f"{key}={typed}"],
                                    [f"{PART_NAMED.get(key, key)}=", shown]))
                rows += schema_rows(group, name, others, key, value) + sweep_rows(group, name, others, key, value)
                if group == "estimator" and key.count(".") == 1 and name in API_ESTIMATORS:
                    option = key.partition(".")[2]
                    for typed, shown in bad_values(key, target):
                        value = {"abc": "abc", "nan": float("nan"), "inf": float("inf")}.get(typed, typed)
                        value = int(value) if typed in ("-1", "0") else value
                        rows.append(row("api", api(estimator=name, **{option: value}), [f"{option}=", shown]))
    return rows


def schema_rows(group: str, name: str, others: list, key: str, value) -> list:
    """Issue 41's generated rows of one numeric key: a quoted number (a text), and, by its type, 1e30 for an
    integer, 1e-320 (a subnormal) for a float."""
    head = [f"{group}={name}", *others]
    out = [row("run", [*head, f"{key}='1'"], [f"{key}='1'", "not a text"])]
    if isinstance(value, int):
        return out + [row("run", [*head, f"{key}=1e30"], [f"{key}=", "1e+15"])]
    return out + [row("run", [*head, f"{key}=1e-320"], [f"{key}=1e-320", "1e-100"])]


def sweep_rows(group: str, name: str, others: list, key: str, value) -> list:
    """Issue 41's generated sweep rows of one numeric key: its default and a bad value in one ``-m`` list (a text,
    NaN), refused before the first job runs, naming the bad job's value."""
    head = ["-m", f"{group}={name}", *others]
    return [row("sweep", [*head, f"{key}={value!r},{typed}"], [f"{PART_NAMED.get(key, key)}=", typed])
            for typed in ("abc", "nan")]


def calibrate_rows() -> list:
    """Issue 41's generated rows of ``magexp calibrate``: every key of its schema given twice and, by its type,
    an integer 1e30, a float 1e-320 or an empty text."""
    from magexp.calibration.options import rows as option_rows

    out = []
    for key, kind, default, _ in option_rows():
        head = ["data.path=good.csv", "data.unit=uT"] if key != "data.unit" else ["data.path=good.csv"]
        if kind == "group" or key in ("data.path", "data.serial", "out"):
            continue
        bad = {"int": "1e30", "float": "1e-320", "float or null": "1e-320", "int or null": "1e30"}.get(kind, "")
        shown = {"1e30": "1e+15", "1e-320": "1e-100", "": "''"}[bad]
        if kind.startswith("[") or kind == "bool":
            continue
        out.append(row("calibrate", [*head, f"{key}={bad}"], [f"{key}=", shown]))
        if kind in ("int", "float", "int or null", "float or null"):
            out.append(row("calibrate", [*head, f"{key}=abc"], [f"{key}=", "abc"]))
    out.append(row("calibrate", ["data.path=good.csv", "folds=2", "folds=3"], ["folds given twice"]))
    return out


#: the estimators that calibrate a recording (the scalar objective's), each given bad options through the API
API_ESTIMATORS = ("cmaes", "de", "ellipsoid_specific", "ipso", "lm", "local", "ml_scalar", "pso", "rdpso",
                  "triangular", "twostep")

TABLE += generated_rows() + calibrate_rows()


def spec_mistake(mistake: str, words: list[str]):
    """A row: ``magexp reproduce toy --tiny`` of the toy paper with one spec mistake (:data:`SPEC_MISTAKES`)."""
    return row("reproduce", ["toy", "--tiny", "--out", "fresh"], words,
               patch=[("magexp.artifacts.paper_spec.EXPERIMENTS", Path("specs", mistake))])


TABLE += [  # ---- a spec checked whole before any run (issue 44 item 2)
    spec_mistake("unknown_column", ["toy_fig1.claims[falls].metric=", "'offset_eror'", "nearest: offset_error"]),
    spec_mistake("dotted_typo", ["toy_fig1.claims[falls].metric=", "'scenario.n_reading'", "scenario.n_readings"]),
    spec_mistake("cells_none", ["toy_fig1.claims[order].cells[0]=", "2000", "selects no planned cell", "[20, 200]"]),
    spec_mistake("where_none", ["toy_fig1.claims[falls].where=", "selects no planned cell", "[20, 200]"]),
    spec_mistake("where_key", ["toy_fig1.claims[falls].where=", "'scenario.nreadings'", "scenario.n_readings"]),
    spec_mistake("match_none", ["toy_fig1.reported[0]", "match=", "21", "selects no planned cell", "[20, 200]"]),
    spec_mistake("headline_part", ["toy/paper.yaml", "'falls'", "'toy_fig1.fall'", "toy_fig1 has claims falls, order"]),
]

CATEGORIES = ("clean", "not one line", "wrote something", "wrong result")

#: the rows of each entry point that make test runs at most, evenly spaced over the table (:func:`in_make_test`)
QUOTA = {"run": 20, "sweep": 3, "calibrate": 8, "reproduce": 4, "api": 10}


def family(case) -> tuple:
    """The entry point, the exit code and the top-level key a row's bad value is given to: its last option's
    (``--jobs``) or last argument's (``scenario`` of ``scenario.noise=-1``); for the API the first word its
    line must hold (``seed`` of ``seed=True``)."""
    entry, args, words, code, _ = case
    if entry == "api":
        named = str(words[0]) if words else ""
    else:
        options = [a for a in map(str, args) if a.startswith("--")]
        named = options[-1] if options else str(args[-1]) if args else ""
    return entry, code, re.split(r"[.=\[(: ]", named.lstrip("+~"), maxsplit=1)[0]


def in_make_test(table) -> list[bool]:
    """Whether each row of ``table`` runs in make test (the others in make test-full): of each entry point's
    rows in table order, :data:`QUOTA` evenly spaced ones (its first and last among them), and the first row of
    each :func:`family`. A rule, not a random draw: the same rows on every run and machine; rows added to the
    table add to make test only when they open a new family."""
    rows: dict[str, list[int]] = {}
    for i, case in enumerate(table):
        rows.setdefault(case[0], []).append(i)
    chosen = set()
    for entry, indices in rows.items():
        n, quota = len(indices), min(QUOTA.get(entry, 1), len(indices))
        chosen |= {indices[round(k * (n - 1) / max(quota - 1, 1))] for k in range(quota)}
    firsts: dict[tuple, int] = {}
    for i, case in enumerate(table):
        firsts.setdefault(family(case), i)
    chosen |= set(firsts.values())
    return [i in chosen for i in range(len(table))]


def case_id(case) -> str:
    entry, args, *_ = case
    if entry == "api":
        return f"api-{TABLE.index(case)}"
    return f"{entry}: " + " ".join(map(str, args)).replace(str(RESULTS), "<results>")


def make_workdir(folder: Path) -> Path:
    """The working folder of a case: the input files, a file, a folder, an output folder that holds
    a calibration already, and a link into ``results/``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in FILES.items():
        (folder / name).write_text(text)
    for name, text in SPECS.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    (folder / "binary.csv").write_bytes(BINARY)
    (folder / "environ").write_bytes(ENVIRON)
    (folder / "random.bin").write_bytes(np.random.default_rng(0).bytes(4096))  # a .bin file: read as a log
    os.mkfifo(folder / "pipe.fifo")  # a FIFO: a plain open of it blocks until a writer comes, which none does
    if DATAFLASH.is_file():  # the recordings of others: absent from a clone without ../shared/data
        log = bytearray(DATAFLASH.read_bytes())
        log[log.index(b"\xa3\x95", len(log) // 3)] ^= 0x10  # a flipped bit in a message's header, a third of the way in
        (folder / "flipped.bin").write_bytes(bytes(log))
    (folder / "one_line.txt").write_text("1," * 5_000_000)  # 10 MB, one line: read whole, it took 2.4 GB (issue 41)
    (folder / "a_file").write_text("not a folder\n")
    (folder / "a_folder").mkdir()
    (folder / "taken").mkdir()
    (folder / "taken" / "calibration.json").write_text("{}\n")
    (folder / "results_link").symlink_to(RESULTS, target_is_directory=True)
    (folder / "results").symlink_to(RESULTS, target_is_directory=True)  # the commands of issue 19, as typed
    return folder


def snapshot(*folders) -> dict:
    """Every file and folder under ``folders`` (links not followed) with its size and time."""
    seen, todo = {}, [str(f) for f in folders if os.path.isdir(f)]
    while todo:
        with os.scandir(todo.pop()) as entries:
            for entry in entries:
                st = entry.stat(follow_symlinks=False)
                seen[entry.path] = (st.st_size, st.st_mtime_ns)
                if entry.is_dir(follow_symlinks=False):
                    todo.append(entry.path)
    seen["/"] = tuple(sorted(os.listdir("/")))
    return seen


def attempt(entry, args):
    """Run one case; returns ``(code, message)``: an exit code, or for the API the exception's
    name (``MagexpError``) and message, ``0`` when it returned."""
    from magexp.__main__ import main as magexp_main
    from magexp.artifacts.reproduce import main as reproduce_main

    try:
        if entry == "api":
            args()
            return 0, ""
        if entry == "reproduce":
            return reproduce_main(list(args)), ""
        magexp_main(["calibrate", *args] if entry == "calibrate" else list(args))
        return 0, ""
    except SystemExit as exc:
        return (exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 1), ""
    except Exception as exc:  # noqa: BLE001 (an API error, or a command line that raised)
        return type(exc).__name__, str(exc)


def outcome(case, watched, capsys, monkeypatch) -> tuple[str, str]:
    """``(category, what happened)`` of one case (:data:`CATEGORIES`); ``watched``: the folders
    whose tree must not change."""
    entry, args, words, code, patch = case
    before = snapshot(*watched)
    capsys.readouterr()
    with monkeypatch.context() as m, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for target, replacement in patch or ():
            m.setattr(target, replacement)
        got, message = attempt(entry, args)
    out, err = capsys.readouterr()
    after = snapshot(*watched)
    if entry == "api":
        lines = [ln for ln in message.splitlines() if ln.strip()] + [str(w.message) for w in caught]
        expected = "MagexpError"
    else:
        lines = [ln for ln in err.splitlines() if ln.strip()] + [str(w.message) for w in caught]
        expected = code
    text = "\n".join(lines)
    changed = sorted(set(before.items()) ^ set(after.items()))
    if any(p.startswith(str(RESULTS)) for p, _ in changed):
        changed.insert(0, ("results/ changed", None))
    if got == 0:
        wrote = f", wrote {[p for p, _ in changed][:3]}" if changed else ""
        return "wrong result", f"accepted (exit 0){wrote}{': ' + text if text else ''}"
    if changed:
        return "wrote something", f"{got}: changed {[p for p, _ in changed][:3]}; {text[:200]}"
    if got != expected or len(lines) != 1 or "Traceback" in out + err or "error: unexpected" in text:
        return "not one line", f"{got}, {len(lines)} lines: {text[:900]}"
    if any(w not in lines[0] for w in words) or "swordfish" in out + err + message:
        return "not one line", f"{got}: the line lacks {[w for w in words if w not in lines[0]]}: {lines[0]}"
    return "clean", lines[0]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    folder = make_workdir(tmp_path / "work")  # beside the test's own run cache (tmp_path/cache)
    monkeypatch.chdir(folder)
    return folder


def test_table_has_every_case():
    """Issue 41: at least 1,200 command-line and 250 API cases, every numeric key of every config among them."""
    entries = [entry for entry, *_ in TABLE]
    assert sum(e != "api" for e in entries) >= 1200 and entries.count("api") >= 250  # issue 41
    assert set(entries) == {"run", "sweep", "calibrate", "reproduce", "api"}
    generated = {arg.partition("=")[0] for entry, args, *_ in generated_rows() if entry != "api" for arg in args}
    assert {"estimator.velocity_clamp", "estimator.r", "estimator.offset_scale", "scenario.gyro.noise_deg_s",
            "scenario.bias_bound_deg_s", "estimator.velocity.c1.start"} <= generated


def test_make_test_runs_a_bounded_subset_of_the_table_that_holds_every_entry_point_and_exit_code():
    """The rule of :func:`in_make_test`: every entry point and exit code, the first row of every family and of
    each entry point among the rows make test runs, fewer than half the rows; a table ten times as long (its
    rows repeated: no new family) runs no more rows in make test."""
    chosen = [case for case, keep in zip(TABLE, in_make_test(TABLE)) if keep]
    assert {(e, c) for e, _, _, c, _ in chosen} == {(e, c) for e, _, _, c, _ in TABLE}
    assert {family(case) for case in chosen} == {family(case) for case in TABLE}
    assert len(chosen) <= sum(QUOTA.values()) + len({family(case) for case in TABLE}) < len(TABLE) / 2
    longer = TABLE * 10
    assert sum(in_make_test(longer)) <= sum(QUOTA.values()) + len({family(case) for case in TABLE})
    for entry in QUOTA:  # each entry point's first and last row are in
        rows = [i for i, case in enumerate(TABLE) if case[0] == entry]
        assert in_make_test(TABLE)[rows[0]] and in_make_test(TABLE)[rows[-1]]


@pytest.fixture(scope="module")
def _table_folder(tmp_path_factory):
    """The working folder of the table's cases, built once per process: a case leaves it as it found it
    (or fails), so the next case starts from the same tree; ``table_workdir`` rebuilds it after a case
    that changed it."""
    folder = make_workdir(tmp_path_factory.mktemp("table") / "work")
    return folder, snapshot(folder)


@pytest.fixture
def table_workdir(_table_folder, monkeypatch):
    folder, pristine = _table_folder
    monkeypatch.chdir(folder)
    yield folder
    if snapshot(folder) != pristine:  # this case failed by writing: the next one starts clean again
        shutil.rmtree(folder)
        make_workdir(folder)
        pristine.clear()
        pristine.update(snapshot(folder))


def needs_recordings(args) -> None:
    """Skip a case that reads the recordings of others (a ``real_*`` scenario, the damaged DataFlash
    log) where ``../shared/data`` is absent."""
    if ("flipped.bin" in str(args) or "scenario=real_" in str(args)) and not DATAFLASH.is_file():
        pytest.skip(f"{SHARED_DATA} is absent")


@pytest.mark.parametrize("case", [pytest.param(case, id=case_id(case), marks=[] if keep else [pytest.mark.full])
                                  for case, keep in zip(TABLE, in_make_test(TABLE))])
def test_bad_input(case, table_workdir, capsys, monkeypatch):
    needs_recordings(case)
    category, detail = outcome(case, [table_workdir, RESULTS], capsys, monkeypatch)
    assert category == "clean", detail


# ---------------------------------------------------------------------------------------------
# what is not a bad input, and what must still hold beside the table

def test_missing_launcher_extra_names_the_pip_install(workdir, cli, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if "submitit" in name else real(name, *a))
    proc = cli("-m", "hydra/launcher=slurm", "seed=1,2")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert "pip install 'magexp[cluster]'" in proc.stderr and not (workdir / "multirun").exists()


def test_ctrl_c_of_a_run_leaves_no_folder(workdir, cli, monkeypatch):
    monkeypatch.setattr("magexp.run.executor.run_batch", interrupt)
    before = snapshot(workdir)
    for args in (["estimator=ellipsoid"], ["estimator=ellipsoid", "hydra.run.dir=mine/run"]):
        proc = cli(*args)
        assert proc.returncode == 130 and proc.stderr.count("\n") == 1 and "interrupted" in proc.stderr
        assert snapshot(workdir) == before  # the run's folder (and outputs/<date>/, mine/) removed again


def test_a_failed_sweep_keeps_what_its_existing_folder_held(workdir, cli, monkeypatch):
    (workdir / "mine").mkdir()
    (workdir / "mine" / "notes.txt").write_text("mine\n")
    monkeypatch.setattr("magexp.run.sweep.run_many", interrupt)
    proc = cli("-m", "estimator=ellipsoid", "seed=1,2", "hydra.sweep.dir=mine")
    assert proc.returncode == 130
    assert sorted(p.name for p in (workdir / "mine").iterdir()) == ["notes.txt"]  # multirun.yaml removed, notes kept


def test_unexpected_error_is_still_one_line(workdir, cli, monkeypatch):
    def broken(cfg):
        raise RuntimeError("a bug\nsecond line")

    monkeypatch.setattr("magexp.run.executor.run_batch", broken)
    proc = cli("estimator=ellipsoid")
    assert proc.returncode == 3 and proc.stderr.count("\n") == 1
    assert "RuntimeError: a bug" in proc.stderr and "MAGEXP_DEBUG" in proc.stderr


def test_utf8_byte_order_mark_is_accepted(workdir, cli):
    (workdir / "bom.csv").write_bytes(b"\xef\xbb\xbf" + (MOCKUP_HEADER + ROWS).encode())
    proc = cli(*MOCKUP, "scenario.path=bom.csv", f"hydra.run.dir={workdir / 'run'}")
    assert proc.returncode == 0, proc.stderr
    assert "fit_rms" in (workdir / "run" / "metrics.csv").read_text()
    (workdir / "bom.txt").write_bytes(b"\xef\xbb\xbf" + PLAIN.encode())  # plain numbers, with a BOM
    from magexp.calibration.command import calibrate_config
    from magexp.core.recordings import load_recording

    rec = load_recording("bom.txt", unit=calibrate_config(["data.unit=µT"]).data.unit)  # µT: the alias of uT
    assert rec.unit == "uT" and rec.readings.shape == (60, 3) and rec.meta["format"] == "plain 3 columns"


def test_valid_edges_are_accepted(workdir, cli):
    """The guards refuse only what they name: a folder beside results/ whose name starts the same,
    an inclination of exactly 90 degrees, folds=0 and a sweep sub-folder with no '..'."""
    beside = RESULTS.parent / f"{RESULTS.name}_not_inside"
    from magexp.run.folders import check_destination

    assert check_destination(beside, "--out") == beside.resolve()
    assert check_destination(RESULTS, "--out", canonical=True) == RESULTS.resolve()
    proc = cli("estimator=ellipsoid", "scenario.field.inclination=90", "write_history=false", "hydra.run.dir=r")
    assert proc.returncode == 0, proc.stderr
    assert not (workdir / "r" / "history.csv").exists()
    proc = cli("-m", "estimator=ellipsoid", "seed=1,2", "hydra.sweep.dir=s", "hydra.sweep.subdir=job_${hydra.job.num}",
               "hydra.launcher.jobs=1")
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in (workdir / "s").iterdir() if p.is_dir()) == ["job_0", "job_1"]


@pytest.mark.parametrize("args", [
    ["-m", "magexp", "calibrate", "data.path=good.csv", "folds=abc"],
    pytest.param(["-m", "magexp.artifacts.reproduce", "ding2024", "--jobs", "abc"], marks=pytest.mark.full),
    # pymavlink's indexer prints on the file descriptors themselves, which only a process shows
    pytest.param(["-m", "magexp", "calibrate", "data.path=random.bin"], marks=pytest.mark.full),
    ["-m", "magexp", "calibrate", "data.path=flipped.bin"],
], ids=lambda a: " ".join(a[1:]))  # make test: a command line and a DataFlash log; test-full: all
def test_bad_input_in_a_process(workdir, args):
    """The process boundary: the same one line, exit 2, from a real ``python -m ...``."""
    needs_recordings(args)
    proc = subprocess.run([sys.executable, *args], cwd=workdir, capture_output=True, text=True,
                          env={**os.environ, "MAGEXP_CACHE": str(workdir.parent / "cache")})
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: "), proc.stderr


def test_a_users_plugin_class_is_a_target_and_nothing_else_is_imported(tmp_path, monkeypatch):
    """docs/extending.md's ``_target_: mypackage.MyMethod`` passes the target check; a user module that
    does not define the named class at its top level is refused without being imported (its import
    would run its code), as are Python's own modules and functions."""
    from magexp.run.targets import check_target

    pkg = tmp_path / "mypackage"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from magexp.estimators.lm import LevenbergMarquardt\n\n\n"
                                     "class MyMethod(LevenbergMarquardt):\n    pass\n")
    (tmp_path / "loud.py").write_text("open(__file__ + '.imported', 'w').close()\n\n\ndef X():\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    check_target("estimator", "mypackage.MyMethod")
    for target in ("loud.X", "os.system", "builtins.eval", "mypackage.LevenbergMarquardt.fit"):
        with pytest.raises(MagexpError):
            check_target("estimator", target)
    assert not (tmp_path / "loud.py.imported").exists()
    with pytest.raises(MagexpError, match="SweepTable"):
        check_target("hydra.callbacks.x", "mypackage.MyMethod")


def test_a_signal_ends_as_ctrl_c_does(capsys):
    """A command stopped by SIGTERM takes Ctrl-C's path (every cleanup of an interrupted command) and
    ends with one line naming the signal and exit 128 + 15."""
    import signal

    from magexp.errors import Terminated, guarded

    def stopped():
        raise Terminated(signal.SIGTERM)

    with pytest.raises(SystemExit) as exit_:
        guarded(stopped)
    assert exit_.value.code == 143
    assert capsys.readouterr().err.strip().splitlines() == [
        "error: interrupted (SIGTERM); finished runs are cached, rerun the same command to resume"]


@pytest.mark.full  # make test's budget: a slow case (make test-full runs it)
def test_sigterm_during_a_sweep_leaves_nothing(tmp_path):
    """``kill -TERM`` of a sweep's process (issue 34: exit -15, no line, its folder left behind): one line,
    exit 143, and its folder gone (a real process: the signal handlers are the command's)."""
    import signal
    import time

    sweep_dir = tmp_path / "sweep"
    env = dict(os.environ, MAGEXP_CACHE=str(tmp_path / "cache"))
    proc = subprocess.Popen([sys.executable, "-m", "magexp", "-m", "estimator=pso", "seed=range(400)",
                             f"hydra.sweep.dir={sweep_dir}"], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not (sweep_dir / "multirun.yaml").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert err.strip().splitlines() == [
        "error: interrupted (SIGTERM); finished runs are cached, rerun the same command to resume"]
    assert not sweep_dir.exists()


def test_a_sigterm_that_omegaconf_swallows_still_stops_the_command():
    """OmegaConf turns an exception raised inside its update (the signal handler's ``Terminated``) into an
    error of its own about one time in seven (measured with a timer signal), which the composer would
    report as a refused value (exit 2). A stop received before such an error is raised again, so the
    command still ends as the signal asks (in a process of its own: the handlers are a command's)."""
    script = """
import os, signal
from magexp import errors
from magexp.run import compose
cfg = compose.compose_config(["scenario=ding2024_exp1"])
try:
    compose.apply_overrides(cfg, ["scenario.n_readings=many"])
except errors.MagexpError:
    print("refused")
errors.stop_on_signals()
try:
    os.kill(os.getpid(), signal.SIGTERM)
except errors.Terminated:
    print("stopped")
try:
    compose.apply_overrides(cfg, ["scenario.n_readings=many"])
except errors.Terminated as exc:
    print("stopped again", exc.signum)
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert done.stdout.split("\n")[:3] == ["refused", "stopped", "stopped again 15"], done.stdout + done.stderr
