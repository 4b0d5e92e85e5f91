"""Which ``_target_`` a config may name: no code from an override or a config (:func:`check_target`).

A ``_target_`` names one of magexp's plug-in classes or, under ``hydra.launcher`` / ``hydra.sweeper`` /
``hydra.callbacks``, one of :data:`HYDRA_TARGETS`; anything else is refused, in one line, before it is imported
or called. The runner checks every node it builds (:func:`magexp.run.runner.build`), and the entry points every
override before Hydra reads it (:func:`magexp.run.guard.check_override_targets`).

A module of its own, apart from the guards of the entry points (:mod:`magexp.run.guard`): the runner imports it,
so it is part of every run's code (:mod:`magexp.run.codekey`), and an edit of the entry points' guards reruns
nothing.
"""

from __future__ import annotations

import ast
import importlib
import importlib.metadata
import importlib.util
import re
import site
import sys
import sysconfig
from pathlib import Path

from omegaconf import DictConfig, ListConfig

from magexp.errors import MagexpError

#: what a ``_target_`` of Hydra's own nodes may name: the classes of the launchers and sweepers a
#: command line may choose (``hydra/launcher=magexp|basic|joblib|slurm|submitit_*``, ``hydra/sweeper=magexp|basic``)
#: and magexp's sweep table. Compared as strings: nothing is imported to check them.
HYDRA_TARGETS = {
    "hydra.launcher": ("hydra_plugins.magexp_launcher.magexp_launcher.MagexpLauncher",
                       "hydra._internal.core_plugins.basic_launcher.BasicLauncher",
                       "hydra_plugins.hydra_joblib_launcher.joblib_launcher.JoblibLauncher",
                       "hydra_plugins.hydra_submitit_launcher.submitit_launcher.SlurmLauncher",
                       "hydra_plugins.hydra_submitit_launcher.submitit_launcher.LocalLauncher"),
    "hydra.sweeper": ("hydra_plugins.magexp_launcher.magexp_sweeper.MagexpSweeper",
                      "hydra._internal.core_plugins.basic_sweeper.BasicSweeper"),
    "hydra.callbacks": ("magexp.run.sweep.SweepTable",),
}
#: the packages of magexp's plug-in classes (estimators and their strategy pieces, scenarios, problems)
PLUGIN_PACKAGES = ("magexp.estimators.", "magexp.scenarios.", "magexp.problems.")
#: the config nodes whose ``_target_`` builds a plug-in (:func:`check_target`)
PLUGIN_NODES = ("scenario", "estimator", "analysis")
#: the methods that make a class of another package a plug-in without a magexp base (the protocols)
PLUGIN_METHODS = ("fit", "generate", "cost")
_SOURCE_LIMIT = 2 ** 20  # bytes of a user module read to find its class statically


def check_targets(node, where: str, *, plugin: bool = False) -> None:
    """Every ``_target_`` in a config node (a DictConfig or a plain container) at dotted ``where``,
    checked by :func:`check_target` (``plugin``: the node builds a plug-in wherever it sits).

    Parameters
    ----------
    node : DictConfig or dict or list
        The config node.
    where : str
        Its dotted place (``estimator``, ``hydra.launcher``).
    plugin : bool
        Check every target as a plug-in class.

    Raises
    ------
    MagexpError
        One line for the first target refused."""
    if isinstance(node, (dict, DictConfig)):
        for k, v in node.items():
            if k == "_target_":
                check_target(where, v, plugin=plugin)
            else:
                check_targets(v, f"{where}.{k}" if where else str(k), plugin=plugin)
    elif isinstance(node, (list, tuple, ListConfig)):
        for v in node:
            check_targets(v, where, plugin=plugin)


def check_target(where: str, target, *, plugin: bool = False) -> None:
    """Refuse, in one line, a ``_target_`` at ``where`` that is not a class magexp may build.

    * under ``hydra.launcher``, ``hydra.sweeper``, ``hydra.callbacks``: one of :data:`HYDRA_TARGETS`
      (compared as strings);
    * under ``scenario``, ``estimator``, ``analysis``: a class (never a function) defined in magexp's
      plug-in packages (:data:`PLUGIN_PACKAGES`), or a user's class (``mypackage.MyMethod``, as
      docs/extending.md allows) that subclasses one of them or defines a plug-in protocol's method
      (:data:`PLUGIN_METHODS`). A user's module is imported only once its source, found on
      ``sys.path`` without importing anything, defines that class at its top level, and only if
      it is not part of Python or of a package installed beside it that does not require magexp
      (:func:`_user_module_source`): ``os.system``, ``numpy.savetxt``, ``subprocess.Popen`` are
      refused without an import. Nothing named is ever called here;
    * anywhere else: refused (``plugin``: the node is known to build a plug-in, as
      :func:`magexp.run.runner.build` says, and is checked as one wherever it sits).

    Parameters
    ----------
    where : str
        The dotted place of the node holding the target.
    target : str
        The ``_target_`` value.
    plugin : bool
        Check it as a plug-in class wherever it sits.

    Returns
    -------
    None
        Nothing: an allowed target passes.

    Raises
    ------
    MagexpError
        One line naming ``where``, the target and what is allowed there.
    """
    text = str(target)
    shown = f"{where}._target_={text[:60]!r}"
    head = where.split(".")[0]
    if head == "hydra" and not plugin:
        return _check_hydra_target(where, text, shown)
    if head not in PLUGIN_NODES and not plugin:
        raise MagexpError(f"{shown} is not allowed: only scenario, estimator and analysis nodes build objects")
    obj = _named_class(text, shown)
    bases = [c for c in obj.__mro__ if c.__module__.startswith(PLUGIN_PACKAGES)]
    own = text.startswith("magexp.")
    if own and (not bases or bases[0] is not obj) or not own and not bases and not any(
            callable(getattr(obj, m, None)) for m in PLUGIN_METHODS):
        raise MagexpError(f"{shown} is not allowed: it is not one of magexp's plug-in classes (estimators, scenarios, "
                          "problems and their pieces) nor a subclass of one")


def _check_hydra_target(where: str, text: str, shown: str) -> None:
    """A ``_target_`` of Hydra's own nodes: one of :data:`HYDRA_TARGETS` (compared as a string)."""
    group = next((g for g in HYDRA_TARGETS if where == g or where.startswith(g + ".")), None)
    allowed = HYDRA_TARGETS.get(group, ())
    if text not in allowed:
        raise MagexpError(f"{shown} is not allowed: " + (f"choose one of {', '.join(allowed)}" if allowed else
                                                         "this Hydra setting takes no _target_"))


def _named_class(text: str, shown: str) -> type:
    """The class a ``_target_`` names, imported only if it is magexp's or passes :func:`_user_module_source`."""
    parts = text.split(".")
    if len(parts) < 2 or not all(p.isidentifier() for p in parts):
        raise MagexpError(f"{shown} is not allowed: a _target_ is a class's dotted name, e.g. "
                          "magexp.estimators.lm.LevenbergMarquardt or mypackage.MyMethod")
    module_name, name = ".".join(parts[:-1]), parts[-1]
    if not text.startswith("magexp.") and not _user_module_source(module_name, name):
        raise MagexpError(f"{shown} is not allowed: it names no class of magexp's estimators, scenarios or problems "
                          "nor a class of your own package defined at its top level (docs/extending.md)")
    try:
        obj = getattr(importlib.import_module(module_name), name, None)
    except Exception as exc:
        raise MagexpError(f"{shown} is not allowed: its module cannot be imported ({type(exc).__name__})") from None
    if not isinstance(obj, type):
        raise MagexpError(f"{shown} is not allowed: it is not a class (a _target_ builds an estimator, a scenario "
                          "or one of their pieces)")
    return obj


def _user_module_source(module_name: str, name: str) -> bool:
    """Whether ``module_name`` is a user's module whose source defines ``class <name>`` at its top
    level, found without importing anything (:func:`_user_package`, then down its folders)."""
    top, *rest = module_name.split(".")
    source = _user_package(top)
    for part in rest:  # down the package's folders, importing nothing
        folder = source.parent if source is not None and source.name == "__init__.py" else None
        if folder is None:
            return False
        source = next((c for c in (folder / f"{part}.py", folder / part / "__init__.py") if c.is_file()), None)
    try:
        if source is None or not source.is_file() or source.stat().st_size > _SOURCE_LIMIT:
            return False
        tree = ast.parse(source.read_bytes())
    except (OSError, SyntaxError, ValueError):
        return False
    return any(isinstance(n, ast.ClassDef) and n.name == name for n in tree.body)


def _user_package(top: str) -> Path | None:
    """The source file of top-level module ``top`` if it is a user's (located, not imported): not
    Python's own, and either outside the interpreter's installation (the working folder,
    ``PYTHONPATH``) or an installed distribution that requires magexp."""
    if top in sys.stdlib_module_names or top in sys.builtin_module_names or top in ("magexp", "hydra_plugins"):
        return None
    try:
        spec = importlib.util.find_spec(top)  # a top-level name: located, not imported
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin or not Path(spec.origin).is_file():
        return None
    where = Path(spec.origin).resolve()
    installed = {Path(p).resolve() for p in (*site.getsitepackages(), site.getusersitepackages(),
                                              sysconfig.get_paths()["stdlib"], sysconfig.get_paths()["platstdlib"])}
    if any(p in where.parents for p in installed):
        dists = importlib.metadata.packages_distributions().get(top, [])
        if not any(re.match(r"magexp\b", req) for d in dists for req in (importlib.metadata.requires(d) or [])):
            return None
    return where
