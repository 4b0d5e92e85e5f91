"""Scenarios: configs that produce a :class:`magexp.core.dataset.Dataset`.

A scenario is built from ``conf/scenario/<name>.yaml`` by ``_target_`` and
exposes ``generate(rng=...) -> Dataset``, ``objective`` (the problem it is
calibrated with by default) and ``search`` (the box estimators search in).
"""
