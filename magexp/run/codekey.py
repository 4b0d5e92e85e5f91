"""The code a run executes, found from the sources without importing them, and its hash.

A run executes (:func:`code_files`) the modules of the classes its config names by ``_target_`` (scenario,
estimator, their nested strategy objects, an analysis step) and of its objective's problem class, with their
static import closure inside magexp and inside the class's own top-level package, and the core every run
executes (:data:`CORE`: the runner and its closure). A class of another package (``_target_:
mypackage.MyMethod``) brings its module's file and the modules it imports of its own package and of magexp.
Modules are found from their source, never imported. So an estimator edit reruns the runs of that estimator
and of the estimators importing its module, an unused new module reruns nothing, and code downstream of a run
(``plots/``, ``summary``, ``report``, ``reproduce``, the executor, the run cache itself) is not part of any
key. Which targets a run names (its ``_target_`` strings, the readers of its data files, its problem class) is
:func:`magexp.run.cache.run_targets`'s.

:func:`code_hash` hashes the name and the executed content of each of those files (the syntax tree without
docstrings and comments: editing a docstring, a comment or a line's layout reruns nothing);
:mod:`magexp.run.cache` keeps the hashes (``code-version.json``, under the sources' :func:`source_stamp`) and
puts them in every run's key.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
from functools import lru_cache
from pathlib import Path

from magexp.paths import ROOT

#: the modules every run executes whatever its config: the runner, which builds the config's objects,
#: makes the problem, fits and evaluates (with its import closure: metrics, bounds, seeding, the bases)
CORE = ("magexp.run.runner",)


@lru_cache(maxsize=None)
def _top_spec(top: str):
    """The import spec of the top-level module or package ``top``, or None. Finding the spec of a
    top-level name executes nothing (that of a submodule would import its parent packages)."""
    try:
        return importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return None


@lru_cache(maxsize=None)
def _source(name: str) -> Path | None:
    """The source file of module ``name`` (a module's ``.py`` or a package's ``__init__.py``), or None.

    Found without importing anything: magexp's under :data:`ROOT`, another package's in the folders
    its top-level package's spec names (:func:`_top_spec`), as the import system finds a module of
    plain source folders. A module found another way (a zip, a ``__path__`` its package extends
    when imported) is not found here."""
    top, *rest = name.split(".")
    if top == "magexp":
        folders = [ROOT / "magexp"]
    else:
        spec = _top_spec(top)
        if spec is None:
            return None
        if not rest:
            origin = Path(spec.origin) if spec.has_location and spec.origin else None
            return origin if origin is not None and origin.is_file() else None
        folders = [Path(p) for p in spec.submodule_search_locations or ()]
    for folder in folders:
        base = folder.joinpath(*rest)
        for path in ((base.with_suffix(".py"),) if rest else ()) + (base / "__init__.py",):
            if path.is_file():
                return path
    return None


def _statements(nodes):
    """Every statement of ``nodes`` and of the blocks inside them (an import is a statement: the
    expressions, most of a module's nodes, are not visited)."""
    for node in nodes:
        yield node
        for block in ("body", "orelse", "finalbody", "handlers", "cases"):
            yield from _statements(getattr(node, block, ()))


@lru_cache(maxsize=None)
def _parse(path: Path) -> ast.Module:
    """The syntax tree of the Python source ``path``; an empty module for a file that is not valid
    Python source (a compiled module; a syntax error, which the run itself then reports)."""
    try:
        return ast.parse(path.read_bytes(), filename=str(path))
    except (SyntaxError, ValueError):
        return ast.Module(body=[], type_ignores=[])


def _imports(path: Path, name: str) -> frozenset[str]:
    """Every module that ``path`` (module ``name``) imports anywhere (function bodies included),
    relative imports made absolute; ``from pkg import x`` names ``pkg.x`` too (``x`` may be a module)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    names = set()
    for node in _statements(_parse(path).body):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                module = ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            names.add(module)
            names.update(f"{module}.{a.name}" for a in node.names)
    return frozenset(names)


@lru_cache(maxsize=None)
def _deps(name: str) -> tuple[str, ...]:
    """The modules executed with module ``name``: its parent packages, and those it imports of magexp
    and of its own top-level package (the standard library, numpy, ... are not followed). The
    top-level ``magexp/__init__.py``'s imports are not followed either (they serve the API, not a run)."""
    parts = name.split(".")
    parents = {".".join(parts[:i]) for i in range(1, len(parts))}
    path = _source(name)
    if path is None or name == "magexp":
        return tuple(sorted(parents))
    own = ("magexp", parts[0])
    found = {n for n in _imports(path, name) if n.partition(".")[0] in own and _source(n) is not None}
    return tuple(sorted(parents | found))


def _target_module(target: str) -> str | None:
    """The module a ``_target_`` (``package.module.Class``) is taken from: its longest prefix with a source."""
    parts = target.split(".")
    return next((m for m in (".".join(parts[:i]) for i in range(len(parts) - 1, 0, -1)) if _source(m)), None)


def code_files(targets=()) -> dict[str, Path]:
    """The source files a run executes, by module name: the import closure (:func:`_deps`) of
    :data:`CORE` and of the modules of ``targets`` (``_target_`` strings, :func:`magexp.run.cache.run_targets`)."""
    todo = list(CORE) + [m for m in map(_target_module, targets) if m is not None]
    found: dict[str, Path] = {}
    while todo:
        name = todo.pop()
        if name not in found and (path := _source(name)) is not None:
            found[name] = path
            todo.extend(_deps(name))
    return dict(sorted(found.items()))


def _fixed_objective(cls: ast.ClassDef) -> str | None:
    """The objective a class body fixes: a class attribute ``objective = "..."``, or the default of
    an ``objective`` argument of its ``__init__``; None if neither."""
    for node in cls.body:
        value = None
        if isinstance(node, ast.FunctionDef) and node.name == "__init__":
            a = node.args
            pairs = [*zip([*a.posonlyargs, *a.args][::-1], a.defaults[::-1]), *zip(a.kwonlyargs, a.kw_defaults)]
            value = next((default for arg, default in pairs if arg.arg == "objective"), None)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            names = node.targets if isinstance(node, ast.Assign) else [node.target]
            value = node.value if any(getattr(n, "id", None) == "objective" for n in names) else None
        if isinstance(value, ast.Constant) and isinstance(value.value, str):
            return value.value
    return None


@lru_cache(maxsize=None)
def default_objective(target: str) -> str | None:
    """The objective that the scenario class ``target`` fixes when its config names none, read from
    its module's source (:func:`_fixed_objective` of the class, else of its base classes defined in the
    same module); None if not found so."""
    module = _target_module(target)
    name = target[len(module) + 1:] if module is not None else ""
    if not name or "." in name:
        return None
    classes = {n.name: n for n in _parse(_source(module)).body if isinstance(n, ast.ClassDef)}
    todo, seen = [name], set()
    while todo:
        name = todo.pop(0)
        if name in seen or name not in classes:
            continue
        seen.add(name)
        found = _fixed_objective(classes[name])
        if found is not None:
            return found
        todo.extend(b.id for b in classes[name].bases if isinstance(b, ast.Name))
    return None


class _NoDocstrings(ast.NodeTransformer):
    """Drops the docstring of a module, class or function: text a run does not execute."""

    def generic_visit(self, node):
        """``node`` with its docstring dropped (a module's, class's or function's), its children visited."""
        body = getattr(node, "body", None)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and body \
                and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                and isinstance(body[0].value.value, str):
            node.body = body[1:] or [ast.Pass()]
        return super().generic_visit(node)


@lru_cache(maxsize=None)
def _digest(path: Path) -> str:
    """The hash of what ``path`` executes: its syntax tree without docstrings, line numbers or comments (so
    documenting or reformatting a module reruns nothing); of its bytes if it is not valid Python source."""
    data = path.read_bytes()
    try:
        tree = ast.parse(data, filename=str(path))
    except (SyntaxError, ValueError):
        return hashlib.sha256(data).hexdigest()
    return hashlib.sha256(ast.dump(_NoDocstrings().visit(tree)).encode()).hexdigest()


def code_hash(targets: tuple[str, ...]) -> str:
    """Hash of the name and executed content (:func:`_digest`) of each file of :func:`code_files`."""
    h = hashlib.sha256()
    for name, path in code_files(targets).items():
        h.update(f"{name}\0{_digest(path)}\n".encode())
    return h.hexdigest()[:16]


def source_stamp() -> str:
    """A digest of where the package's sources are and of every ``.py`` file's path, size,
    modification time and inode: any edit, checkout or copy changes it (cheap: stats, no reads)."""
    h = hashlib.sha256(str(ROOT).encode())
    for path in sorted((ROOT / "magexp").rglob("*.py")):
        st = path.stat()
        h.update(f"{path.relative_to(ROOT).as_posix()}\0{st.st_size}\0{st.st_mtime_ns}\0{st.st_ino}\n".encode())
    return h.hexdigest()[:32]


def forget_code() -> None:
    """Forget what this process found of the sources (files, imports, digests): for a process that
    edits sources, or changes ``sys.path``, and keys runs again."""
    for cached in (_top_spec, _source, _parse, _deps, default_objective, _digest):
        cached.cache_clear()
