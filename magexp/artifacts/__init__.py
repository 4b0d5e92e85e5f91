"""The artifact language: a paper's figures and tables declared as YAML specs
(``experiments/<paper>/*.yaml``), planned into runs, run through :mod:`magexp.run`, summarised into
verdicts and claims, drawn, and written up in ``results/REPORT.md``.

Lives here: :mod:`~magexp.artifacts.spec` (the typed spec), :mod:`~magexp.artifacts.plan` (spec → runs →
tidy rows), :mod:`~magexp.artifacts.reproduce` (``magexp reproduce``), :mod:`~magexp.artifacts.tables`
(every aggregation over runs: medians, quantiles, success fractions, the one interval helper) and
:mod:`~magexp.artifacts.kinds` (one module per artifact kind: its plot keys, its table, its figure), :mod:`~magexp.artifacts.summary`
(verdicts), :mod:`~magexp.artifacts.claims`, :mod:`~magexp.artifacts.headlines` (a paper's headline claims
judged), :mod:`~magexp.artifacts.report`, :mod:`~magexp.artifacts.formats` (the results files' CSV and table
formats), :mod:`~magexp.artifacts.verify` (``magexp verify``) and :mod:`~magexp.artifacts.compare` (two results
folders compared), and :mod:`~magexp.artifacts.plots` (one module per figure kind: drawing only).

May import: ``core``, ``run``, ``problems`` (a problem's class, to tell whether an estimator applies;
the facts a verdict needs come from the stored runs, never a simulation) and
:mod:`magexp.estimators.base` (whether an estimator applies, by class); never ``calibration``.
"""
