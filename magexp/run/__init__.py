"""Running configurations: compose them with Hydra, check them before any work starts, run them through the run
cache on one process, many, or a Dask cluster, and sweep them.

Lives here: :mod:`~magexp.run.command` (``magexp [KEY=VALUE ...]``: one run, a sweep),
:mod:`~magexp.run.outputs` (a run's folder and printed table), :mod:`~magexp.run.threads` (one BLAS thread,
set by the entry point), :mod:`~magexp.run.compose` (Hydra composition and the typed scenario schemas),
:mod:`~magexp.run.preflight` (checks before a command starts), :mod:`~magexp.run.guard` (what may be written
where), :mod:`~magexp.run.targets` (which ``_target_`` a config may name), :mod:`~magexp.run.budget` (work
bounded before it starts), :mod:`~magexp.run.runner` (one config → one fit), :mod:`~magexp.run.executor` (many
runs), :mod:`~magexp.run.cache` (finished runs, keyed by config, data and code; :mod:`~magexp.run.codekey`:
the code a run executes), :mod:`~magexp.run.sweep` (``-m`` sweeps), :mod:`~magexp.run.progress`,
:mod:`~magexp.run.provenance`.

May import: ``core``, ``scenarios``, ``problems``, ``estimators`` (by name, through Hydra), Hydra, OmegaConf,
Dask (lazily), and other ``run`` modules.
"""
