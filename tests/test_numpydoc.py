"""The public API of the estimators is documented the numpydoc way (issue 35): every public function and
method of ``magexp.estimators`` that takes parameters has a ``Parameters`` section naming each of them,
and a class's docstring names its constructor's (numpydoc's convention).

A small parser of numpydoc sections (numpydoc itself is not a dependency): a section is a title line
followed by a line of dashes; an entry of ``Parameters`` is a line at the section's indentation,
``name : type`` or ``name1, name2 : type`` (``*args``, ``**settings`` allowed)."""

import importlib
import inspect
import pkgutil
import re
from dataclasses import is_dataclass

import pytest

import magexp.estimators

#: modules left out (the private ``_compiled``, whose kernels are not public API, is left out by its name)
SKIP: set = set()


def sections(doc: str) -> dict[str, list[str]]:
    """``{title: lines}`` of the numpydoc sections of ``doc`` (dedented)."""
    lines = inspect.cleandoc(doc or "").splitlines()
    out, title = {}, None
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and line.strip() and re.fullmatch(r"-{3,}", lines[i + 1].strip()) \
                and len(lines[i + 1].strip()) == len(line.strip()):
            title = line.strip()
            out[title] = []
        elif title is not None and not re.fullmatch(r"-{3,}", line.strip()):
            out[title].append(line)
    return out


def documented(doc: str) -> set[str]:
    """The parameter names the ``Parameters`` section of ``doc`` documents."""
    names = set()
    for line in sections(doc).get("Parameters", []):
        if line and not line[0].isspace():
            head = line.split(" : ")[0]
            names |= {n.strip().lstrip("*") for n in head.split(",") if n.strip()}
    return names


def parameters(func) -> list[str]:
    """The parameters a caller passes (not ``self``, ``cls``)."""
    return [p for p in inspect.signature(func).parameters if p not in ("self", "cls")]


def public_api() -> list[tuple[str, object, object]]:
    """``(name, callable, docstring owner)`` of every public function, method and constructor of the
    estimators (a constructor is documented by its class's docstring)."""
    out = []
    for info in pkgutil.iter_modules(magexp.estimators.__path__, "magexp.estimators."):
        if info.name.rpartition(".")[2] in SKIP or info.name.rpartition(".")[2].startswith("_"):
            continue
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            obj = getattr(obj, "py_func", obj)  # a compiled kernel: its Python function
            if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
                continue
            if inspect.isfunction(obj):
                out.append((f"{info.name}.{name}", obj, obj))
            elif inspect.isclass(obj) and not is_dataclass(obj):  # a dataclass documents its fields as Attributes
                if "__init__" in vars(obj) and not getattr(obj, "_is_protocol", False):
                    out.append((f"{info.name}.{name}", obj.__init__, obj))
                for attr, member in vars(obj).items():
                    func = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
                    if inspect.isfunction(func) and (not attr.startswith("_") or attr == "__call__"):
                        out.append((f"{info.name}.{name}.{attr}", func, func))
    return out


API = public_api()


def test_the_api_is_found():
    names = {n for n, _, _ in API}
    assert {"magexp.estimators.lm.LevenbergMarquardt.fit", "magexp.estimators.lm.LevenbergMarquardt",
            "magexp.estimators.kalman.kalman_update", "magexp.estimators.base.applies_to"} <= names
    assert len(API) > 80


@pytest.mark.parametrize("name, func, owner", API, ids=[n for n, _, _ in API])
def test_every_public_callable_documents_its_parameters(name, func, owner):
    wanted = parameters(func)
    if not wanted:
        return
    missing = [p for p in wanted if p not in documented(owner.__doc__)]
    assert not missing, f"{name}: the Parameters section does not name {missing}"


def test_the_parser_reads_numpydoc():
    doc = """Summary.

    Parameters
    ----------
    a, b : float
        Two.
    *args
        More.
    c : int

    Returns
    -------
    int
    """
    assert documented(doc) == {"a", "b", "args", "c"} and sections(doc)["Returns"][0] == "int"
    assert documented("Summary.\n\nname : config name.\n") == set()  # no section, no parameters
