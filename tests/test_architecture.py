"""Rules of the house that a script can check."""

import ast
import re
from pathlib import Path

TESTS = Path(__file__).parent

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
