"""magexp's version, its one home: ``magexp.__version__``, the provenance of every output
(:mod:`magexp.run.provenance`) and ``pyproject.toml`` read it from here (a module that imports nothing,
so that reading the version never imports the package's API back)."""

__version__ = "0.1.0"
