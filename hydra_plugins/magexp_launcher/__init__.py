"""magexp's Hydra launcher: ``-m`` sweeps through :mod:`magexp.executor` (see :mod:`.magexp_launcher`)."""
