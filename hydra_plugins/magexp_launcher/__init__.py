"""magexp's Hydra launcher: ``-m`` sweeps through :mod:`magexp.run.executor` (see :mod:`.magexp_launcher`)."""
