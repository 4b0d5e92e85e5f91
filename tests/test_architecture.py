"""The shape of the code: rules of the house that a reviewer would otherwise check by eye."""

import ast
import functools
import re
from pathlib import Path

from radon.complexity import cc_visit

import magexp

ROOT = Path(magexp.__file__).resolve().parent.parent
TESTS = Path(__file__).parent
PACKAGES = (ROOT / "magexp", ROOT / "hydra_plugins")
#: the most branches a function may have (radon's cyclomatic complexity)
MAX_COMPLEXITY = 15


def _functions(blocks):
    """Every function and method among radon's ``blocks``, nested ones included."""
    for block in blocks:
        inner = getattr(block, "methods", None)  # a class: its methods and the classes inside it
        if inner is None:
            yield block
            yield from _functions(block.closures)
        else:
            yield from _functions(inner + block.inner_classes)


def _complexities() -> dict[str, int]:
    """``{"<file>:<function>": cyclomatic complexity}`` of every function of the packages."""
    out = {}
    for package in PACKAGES:
        for path in sorted(package.rglob("*.py")):
            for fn in _functions(cc_visit(path.read_text())):
                key = f"{path.relative_to(ROOT).as_posix()}:{fn.fullname}"
                out[key] = max(fn.complexity, out.get(key, 0))  # a name defined twice: the worse
    return out


def test_no_function_is_too_complex():
    found = _complexities()
    assert len(found) > 500  # the walk saw the package
    over = {name: c for name, c in found.items() if c > MAX_COMPLEXITY}
    assert not over, "cyclomatic complexity above %d (radon): %s" % (
        MAX_COMPLEXITY, ", ".join(f"{name} ({c})" for name, c in sorted(over.items())))


# ---------------------------------------------------------------------------------------------
# the import graph: every import of one magexp module by another, at module top or inside a
# function (a lazy import is still a dependency). Its layers and the absence of cycles are rules; the
# size of a module and the depth of an import chain are signals (issue 42): :func:`report` prints the
# largest and the deepest, and a module is split where a concept ends, never to fit a number

#: the modules allowed directly in magexp/ beside the packages
TOP_MODULES = {"__init__", "__main__", "_version", "errors", "paths"}
#: what each package may import (besides magexp.errors, magexp.paths, magexp._version and itself): data flows one way
MAY_IMPORT = {
    "core": set(),
    "problems": {"core"},
    "scenarios": {"core"},
    "estimators": {"core", "problems"},
    "run": {"core", "problems", "scenarios", "estimators"},
    "artifacts": {"core", "problems", "scenarios", "estimators", "run"},
    "calibration": {"core", "problems", "scenarios", "estimators", "run", "artifacts"},
    "perf": {"core", "problems", "scenarios", "estimators", "run", "artifacts", "calibration"},
    "site": {"core", "problems", "scenarios", "estimators", "run", "artifacts"},
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(node, here: str, is_package: bool, modules: set) -> list[str]:
    """The magexp modules an ``import`` / ``from ... import`` node names (its deepest known module)."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        base = node.module or ""
        if node.level:
            parts = here.split(".")[: len(here.split(".")) - (0 if is_package else 1) - (node.level - 1)]
            base = ".".join([*parts, base] if base else parts)
        names = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
    out = []
    for name in names:
        while name not in modules and "." in name:
            name = name.rsplit(".", 1)[0]
        if name in modules and name.startswith("magexp"):
            out.append(name)
    return out


@functools.cache
def import_graph() -> dict[str, set[str]]:
    """``{module: {magexp modules it imports}}`` over the whole package. An import of the root package
    ``magexp`` itself (``from magexp import __version__``) is not an edge: Python imports a module's
    parent package before the module, whatever the module says."""
    paths = {_module_name(p): p for p in (ROOT / "magexp").rglob("*.py")}
    graph = {}
    for name, path in paths.items():
        tree = ast.parse(path.read_text())
        graph[name] = {target for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                       for target in _resolve(node, name, path.name == "__init__.py", set(paths))
                       if target not in (name, "magexp")}
    return graph


def test_at_most_five_modules_sit_beside_the_packages():
    top = {p.stem for p in (ROOT / "magexp").glob("*.py")}
    assert top <= TOP_MODULES, f"modules directly in magexp/: {sorted(top - TOP_MODULES)}"


def _cycles(graph) -> list[list[str]]:
    """The import cycles of ``graph``: each strongly connected component of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while not component or component[-1] != v:
                component.append(stack.pop())
                on.discard(component[-1])
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _depths(graph) -> dict[str, tuple[str, ...]]:
    """``{module: its longest chain of imports down to a leaf}`` (an import back into the chain, possible only
    inside a cycle, ends it)."""
    chains: dict[str, tuple[str, ...]] = {}

    def chain(module, seen=()):
        if module in chains:
            return chains[module]
        below = [chain(m, (*seen, module)) for m in sorted(graph[module]) if m not in seen and m != module]
        found = (module, *max(below, key=len, default=()))
        if not seen or not any(m in seen for m in graph[module]):
            chains[module] = found
        return found

    for module in sorted(graph):
        chain(module)
    return chains


def test_the_import_graph_has_no_cycle():
    cycles = _cycles(import_graph())
    assert not cycles, "import cycles (imports inside functions count): " + "; ".join(" <-> ".join(c) for c in cycles)


#: how many modules and chains :func:`report` lists
REPORTED = 10


def module_sizes() -> dict[str, int]:
    """``{path under the repository: lines}`` of every module of the package."""
    return {p.relative_to(ROOT).as_posix(): len(p.read_text().splitlines()) for p in (ROOT / "magexp").rglob("*.py")}


def report() -> list[str]:
    """The lines of the architecture report: the :data:`REPORTED` largest modules and the :data:`REPORTED`
    deepest import chains (counting every import, inside functions too), printed by the architecture test
    (``pytest -s``) and at the end of a session that ran it (``tests/conftest.py``)."""
    sizes = sorted(module_sizes().items(), key=lambda item: (-item[1], item[0]))[:REPORTED]
    chains = sorted(_depths(import_graph()).values(), key=lambda c: (-len(c), c))[:REPORTED]
    return ([f"the {REPORTED} largest modules (lines):"] + [f"  {n:5d}  {path}" for path, n in sizes]
            + [f"the {REPORTED} deepest import chains (modules):"] + [f"  {len(c):5d}  {' -> '.join(c)}" for c in chains])


def test_the_report_lists_the_largest_modules_and_the_deepest_chains():
    """A report, not a limit: a module's size and an import chain's depth are printed for a reviewer to
    read; the test fails only if the report cannot be made or misses what it measures."""
    sizes, chains = module_sizes(), _depths(import_graph())
    assert len(sizes) > 100 and len(chains["magexp.__main__"]) > 3  # the walks saw the package and its layers
    lines = report()
    largest = min(sizes.items(), key=lambda item: (-item[1], item[0]))  # the report's order: ties by path
    deepest = max(chains.values(), key=len)
    assert len(lines) == 2 * REPORTED + 2 and largest[0] in lines[1] and str(largest[1]) in lines[1]
    assert lines[REPORTED + 2].split()[0] == str(len(deepest))
    print("\n" + "\n".join(lines))


def test_the_architecture_checks_find_what_they_look_for():
    """The cycle and depth scans on a hand-made graph: a cycle found (and only it), the longest chain measured."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"d"}}
    assert _cycles(graph) == [["a", "b", "c"]]
    line = {"a": {"b", "d"}, "b": {"c"}, "c": {"d"}, "d": set()}
    assert _depths(line)["a"] == ("a", "b", "c", "d") and _depths(line)["c"] == ("c", "d")


def test_packages_import_only_the_layers_below_them():
    wrong = []
    for module, targets in import_graph().items():
        parts = module.split(".")
        if len(parts) < 2 or parts[1] not in MAY_IMPORT:
            continue
        for target in targets:
            package = target.split(".")[1] if target.count(".") else None
            if package and package not in (parts[1], "errors", "paths", "_version") and package not in MAY_IMPORT[parts[1]]:
                wrong.append(f"{module} -> {target}")
    assert not wrong, "imports against the layers: " + ", ".join(sorted(wrong))


# ---------------------------------------------------------------------------------------------
# tests go through public interfaces

#: hand-checked tests of numerical kernels: they may look inside the kernels
KERNEL_TESTS = {"test_kernels.py", "test_swarm_kernels.py", "test_fast_costs.py"}
PRIVATE = re.compile(r"^_(?!_)")  # ``_name``, not a dunder such as ``__version__``
PRIVATE_PATH = re.compile(r"\bmagexp(?:\.\w+)*?\.(_(?!_)\w*)")


def _magexp_names(tree: ast.AST) -> set[str]:
    """The names a test module binds to something imported from magexp."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "magexp":
            names |= {a.asname or a.name for a in node.names}
        elif isinstance(node, ast.Import):
            names |= {a.asname or a.name.split(".")[0] for a in node.names if a.name.split(".")[0] == "magexp"}
    return names


def private_uses(source: str, filename: str = "<test>") -> list[tuple[int, str]]:
    """``(line, text)`` of each use of a ``_``-prefixed magexp name in a test module's source: an import
    (``from magexp.x import _y``, ``import magexp._x``), an attribute of something imported from
    magexp (``module._y``, ``Class._y``), a string naming one (``"magexp.x._y"``, as given to
    ``monkeypatch.setattr`` or ``sys.modules``), or a ``_``-prefixed attribute name given as a
    string beside something imported from magexp (``monkeypatch.setattr(module, "_y", ...)``,
    ``getattr(module, "_y")``)."""
    tree = ast.parse(source, filename)
    bound = _magexp_names(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "magexp":
            parts = node.module.split(".")
            found += [(node.lineno, f"from {node.module} import {a.name}") for a in node.names
                      if PRIVATE.match(a.name) or any(PRIVATE.match(p) for p in parts)]
        elif isinstance(node, ast.Import):
            found += [(node.lineno, f"import {a.name}") for a in node.names
                      if a.name.split(".")[0] == "magexp" and any(PRIVATE.match(p) for p in a.name.split("."))]
        elif isinstance(node, ast.Attribute) and PRIVATE.match(node.attr):
            base = node.value
            while isinstance(base, ast.Attribute):
                base = base.value
            if isinstance(base, ast.Name) and base.id in bound:
                found.append((node.lineno, ast.unparse(node)))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            found += [(node.lineno, repr(m.group(0))) for m in PRIVATE_PATH.finditer(node.value)]
        elif isinstance(node, ast.Call):
            args = node.args
            for target, name in zip(args, args[1:]):
                if (isinstance(target, ast.Name) and target.id in bound and isinstance(name, ast.Constant)
                        and isinstance(name.value, str) and PRIVATE.match(name.value)):
                    found.append((node.lineno, ast.unparse(node)))
    return sorted(set(found))


def test_the_scan_finds_each_kind_of_private_use():
    source = '''
import magexp.run.compose as compose
from magexp.run import cache, executor
from magexp.artifacts.summary import _row, label_of
import magexp._hidden
monkeypatch.setattr("magexp.run.executor._run_task", f)
monkeypatch.setattr(compose, "_SEEN", set())
sys.modules["magexp.calibration._fit"] = None
x = cache._closure_hash()
y = executor.Thing._private
ok = cache.code_version(), label_of, magexp.__version__, os._exit, "magexp.run.cache", compose.__name__
'''
    found = [text for _, text in private_uses(source)]
    assert found == ["from magexp.artifacts.summary import _row", "import magexp._hidden",
                     "'magexp.run.executor._run_task'", "monkeypatch.setattr(compose, '_SEEN', set())",
                     "'magexp.calibration._fit'", "cache._closure_hash", "executor.Thing._private"]


def test_tests_use_only_public_names_of_magexp():
    """A test outside the numerical-kernel tests goes through magexp's public interface, so a move or
    a rewrite of private helpers that keeps the behaviour breaks no test (issue 20)."""
    offenders = [f"{path.name}:{line}: {text}" for path in sorted(TESTS.glob("*.py"))
                 if path.name not in KERNEL_TESTS and path.name != Path(__file__).name  # its examples above
                 for line, text in private_uses(path.read_text(), str(path))]
    assert not offenders, "private magexp names used by tests:\n" + "\n".join(offenders)
