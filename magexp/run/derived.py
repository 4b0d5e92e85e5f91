"""The namespace of the config schemas :func:`magexp.run.compose.schema_of` derives at run time (so that a
config holding one pickles by name), which derives them when one is looked up before they are: a worker
process of Hydra's joblib launcher unpickles a config before anything in it has composed one."""

from __future__ import annotations

import types


class Derived(types.SimpleNamespace):
    """Derived schemas by name; ``register`` (called on a name not found yet) derives and stores them all.

    Parameters
    ----------
    register : callable
        Derives every schema into this namespace (:func:`magexp.run.compose.register_schemas`).
    """

    def __init__(self, register):
        super().__init__(_register=register)

    def __getattr__(self, name):
        """The schema ``name``, derived first if it is not yet (a worker unpickling a config)."""
        if name.startswith("__"):  # pickle's and copy's probes of special methods
            raise AttributeError(name)
        self._register()
        return object.__getattribute__(self, name)
