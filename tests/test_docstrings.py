"""Numpydoc on the public API: every public function and method of ``magexp.calibration``, ``magexp.core``,
``magexp.problems`` and of what ``magexp`` exports (``calibrate``, ``Calibration``, ``FitResult``) has a
``Parameters`` section when it takes parameters, and a ``Returns`` section when it returns a value (issue 35: 1 %
of public functions had them)."""

import ast
import re
from pathlib import Path

import pytest

import magexp

PACKAGE = Path(magexp.__file__).resolve().parent
#: the modules checked: the calibration, core (its readers too) and problems packages, the package root and the
#: estimators' result types.
MODULES = sorted(p for folder in ("calibration", "core", "core/readers", "problems")
                 for p in (PACKAGE / folder).glob("*.py")) + [PACKAGE / "__init__.py", PACKAGE / "estimators" / "result.py"]
SECTION = "^{}\n-+$"


def _public_functions(tree: ast.Module):
    """``(qualified name, node)`` of every public function and method (properties aside: they are attributes)."""
    def visit(body, prefix=""):
        for node in body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                yield from visit(node.body, f"{prefix}{node.name}.")
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                public = not node.name.startswith("_") or node.name in ("__getattr__", "__dir__")
                prop = any(getattr(d, "id", getattr(d, "attr", None)) in ("property", "cached_property")
                           for d in node.decorator_list)
                if public and not prop:
                    yield f"{prefix}{node.name}", node
    yield from visit(tree.body)


def _parameters(node) -> list[str]:
    a = node.args
    names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs) if x.arg not in ("self", "cls")]
    return names + [x.arg for x in (a.vararg, a.kwarg) if x is not None]


def _returns_value(node) -> bool:
    """Whether ``node`` itself (not a function nested in it) returns a value."""
    todo = list(node.body)
    while todo:
        child = todo.pop()
        if isinstance(child, ast.Return) and child.value is not None:
            return True
        if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            todo.extend(ast.iter_child_nodes(child))
    return False


def missing_sections(source: str) -> list[str]:
    """``"name: Section"`` of each public function of ``source`` lacking a section it needs."""
    missing = []
    for name, node in _public_functions(ast.parse(source)):
        doc = ast.get_docstring(node) or ""
        if _parameters(node) and not re.search(SECTION.format("Parameters"), doc, re.M):
            missing.append(f"{name}: Parameters")
        if _returns_value(node) and not re.search(SECTION.format("(Returns|Yields)"), doc, re.M):
            missing.append(f"{name}: Returns")
    return missing


def test_the_check_finds_a_missing_section():
    source = '''
def documented(x):
    """Twice.

    Parameters
    ----------
    x : float
        A number.

    Returns
    -------
    float
        ``2 x``.
    """
    return 2 * x


def bare(x):
    """Twice, undocumented."""
    return 2 * x


class Thing:
    @property
    def size(self):
        """An attribute: no sections needed."""
        return 1

    def apply(self, y):
        """Nothing returned, a parameter undocumented."""
        print(y)


def _private(z):
    return z
'''
    assert missing_sections(source) == ["bare: Parameters", "bare: Returns", "Thing.apply: Parameters"]


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.relative_to(PACKAGE).as_posix())
def test_every_public_function_has_its_numpydoc_sections(path):
    assert missing_sections(path.read_text()) == []
