"""Performance tooling: the speed benchmark (:mod:`~magexp.perf.bench`, ``make bench``) and the warm-up
that compiles the numba kernels once when an environment is created (:mod:`~magexp.perf.warmup`).

May import anything below it; nothing in the product imports ``perf``.
"""
