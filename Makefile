# magexp — every target sets up its own virtual environment on first use.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# the peer MAGYC (magexp/perf/peers): an environment of its own, from requirements-peers.lock
PEERS  ?= .peers/venv
PEERS_STAMP := $(PEERS)/.installed
# the calibration tools pilots use (magcal, circuitpython-mag-cal): their own environment, requirements-peers-tools.lock
TOOLS_VENV ?= .peers/tools-venv
TOOLS_STAMP := $(TOOLS_VENV)/.installed
JOBS   ?= 0
# EXECUTOR=dask runs on a Dask cluster: a local one, or SCHEDULER=tcp://host:8786 | slurm | pbs | sge
EXECUTOR ?= local
SCHEDULER ?=
RUN_ON := --jobs $(JOBS) --executor $(EXECUTOR) $(if $(SCHEDULER),--scheduler $(SCHEDULER))
# tests run in TEST_JOBS processes (pytest-xdist; TEST_JOBS=0: one process), the slowest listed at the end
TEST_JOBS ?= 2
PYTEST := $(PY) -m pytest $(if $(filter-out 0,$(TEST_JOBS)),-n $(TEST_JOBS) --dist worksteal) --durations=15
# Python keeps the bytecode of magexp and of the tests (pytest's rewritten modules) in their __pycache__
# folders, compiled once: a PYTHONDONTWRITEBYTECODE in the caller's environment would have every process of
# make test and make reproduce compile them again (a test worker's collection: 7.6 s instead of 2.7 s)
unexport PYTHONDONTWRITEBYTECODE

.DEFAULT_GOAL := help
.PHONY: help venv lock bench reproduce verify redraw report test test-full docs clean peers peers-lock peers-bench peers-tools peers-tools-bench

help: ## list the targets
	@grep -E '^[a-zA-Z0-9_%-]+:.*## ' $(MAKEFILE_LIST) | awk 'BEGIN {FS = ":.*## "}; {printf "  %-22s %s\n", $$1, $$2}'

$(STAMP): pyproject.toml requirements.lock
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.lock
	$(PY) -m pip install --quiet --no-deps -e .
	$(PY) -m compileall -q magexp
	$(PY) -m magexp.perf.warmup
	@touch $(STAMP)

venv: $(STAMP) ## create .venv and install magexp with its test extras

reproduce: $(STAMP) ## regenerate every figure, table and the report into results/
	$(PY) -m magexp reproduce all $(RUN_ON)

verify: $(STAMP) ## does a reproduction agree with the committed results/? (results/ if reproduced, else one into .cache/verify)
	$(PY) -m magexp verify --jobs $(JOBS)

redraw: $(STAMP) ## rebuild every figure, results/summary.csv and REPORT.md from the CSVs (no run)
	$(PY) -m magexp reproduce all --redraw

reproduce-%: $(STAMP) ## regenerate one paper (a folder of experiments/: ding2024, yuan2018, yan2022, benchmark, real) and the report
	$(PY) -m magexp reproduce $* $(RUN_ON)

report: $(STAMP) ## rebuild results/summary.csv and results/REPORT.md from the artifact CSVs
	$(PY) -m magexp.artifacts.report

bench: $(STAMP) ## speed benchmark; writes results/bench.csv
	$(PY) -m magexp.perf.bench

# make test's budget: 90 s of wall time on two quiet cores (TEST_JOBS=2), after make venv's warm-up, with room for the bad-input
# table to grow. It is kept by testing less in it, never by machinery in magexp for the tests' sake: a slow case, or a
# parametrisation beyond one cheap case of each behaviour, is marked `full` (make test-full); the bad-input table runs
# a fixed subset (tests/test_bad_input.py: in_make_test), the artifacts' smoke runs one per plot family
# (tests/test_artifacts.py: IN_MAKE_TEST)
test: $(STAMP) ## run the test suite in TEST_JOBS=2 processes (without the `full` end-to-end cases: make test-full)
	$(PYTEST) -m "not full"

test-full: $(STAMP) ## the test suite and the `full` end-to-end cases (the wheel installed and run elsewhere)
	$(PYTEST)

# NO_MKDOCS_2_WARNING: without the banner Material for MkDocs prints on every build (its end of life, May 2027)
docs: $(STAMP) ## build the documentation site (docs/, mkdocs.yml) strictly into site/
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --site-dir site

lock: ## refresh requirements.lock from the newest releases allowed by pyproject.toml (then commit it)
	rm -rf .lockenv && $(PYTHON) -m venv .lockenv
	.lockenv/bin/python -m pip install --quiet --upgrade pip
	.lockenv/bin/python -m pip install --quiet '.[all,test,bench,docs]'
	(echo "# Pinned environment for make venv / make test / make reproduce (Python 3.11). Refresh: make lock"; \
	 .lockenv/bin/python -m pip freeze --exclude magexp) > requirements.lock
	rm -rf .lockenv

$(PEERS_STAMP): requirements-peers.lock
	rm -rf $(PEERS) && $(PYTHON) -m venv $(PEERS)
	$(PEERS)/bin/python -m pip install --quiet --upgrade pip
	$(PEERS)/bin/python -m pip install --quiet --no-deps -r requirements-peers.lock
	$(PEERS)/bin/python -c "import magyc"
	@touch $(PEERS_STAMP)

peers: $(PEERS_STAMP) ## build the peer MAGYC's own environment .peers/venv from requirements-peers.lock

peers-bench: $(STAMP) $(PEERS_STAMP) ## magexp beside MAGYC on the same data; writes results/peers/ (minutes)
	nice $(PY) -m magexp.perf.peers.bench --out results/peers

$(TOOLS_STAMP): requirements-peers-tools.lock
	rm -rf $(TOOLS_VENV) && $(PYTHON) -m venv $(TOOLS_VENV)
	$(TOOLS_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(TOOLS_VENV)/bin/python -m pip install --quiet --no-deps -r requirements-peers-tools.lock
	MPLBACKEND=Agg $(TOOLS_VENV)/bin/python -c "import magcal.core, mag_cal"
	@touch $(TOOLS_STAMP)

peers-tools: $(TOOLS_STAMP) ## build the environment of magcal and circuitpython-mag-cal, .peers/tools-venv
peers-tools-bench: $(STAMP) $(TOOLS_STAMP) ## magexp beside magcal and circuitpython-mag-cal on every shared recording: results/peers/tools.md (1 min)
	nice $(PY) -m magexp.perf.peers.tools --out results/peers

peers-lock: ## refresh requirements-peers.lock from the newest magyc release (then commit it)
	rm -rf .lockenv && $(PYTHON) -m venv .lockenv
	.lockenv/bin/python -m pip install --quiet --upgrade pip
	.lockenv/bin/python -m pip install --quiet magyc
	(head -3 requirements-peers.lock; .lockenv/bin/python -m pip freeze) > requirements-peers.lock.new
	mv requirements-peers.lock.new requirements-peers.lock
	rm -rf .lockenv

clean: ## remove the environment, caches and Hydra run folders (never results/)
	rm -rf $(VENV) .peers .cache outputs multirun .pytest_cache *.egg-info build dist site magexp/_resources
