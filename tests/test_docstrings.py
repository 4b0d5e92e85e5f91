"""Docstrings written for their reader (issue 42; issue 35 before it).

The public API (:data:`PUBLIC`: ``magexp.calibrate``, ``Calibration``, ``FitResult``, the estimator and problem
base classes, every class a config of ``conf/estimator/`` builds, the recording readers) has full numpydoc: a
function that takes parameters has a ``Parameters`` section naming each of them (``name : type`` or
``name1, name2 : type``; ``*args``, ``**settings``), one that returns a value a ``Returns`` (or ``Yields``)
section, and a class with a constructor of its own names the constructor's parameters in its docstring
(numpydoc's convention) or in the constructor's. Every other function and class (internal) needs a first
line only, saying what it returns and why it exists. No ``Parameters`` entry anywhere is a bare
``name : type``: a parameter worth a section is described there, once.

Read from the source (the AST), with a small parser of numpydoc sections (numpydoc itself is not a
dependency). A protocol implementation (:data:`PROTOCOLS`: a kind's ``table`` and ``draw``) is checked
against the sections its package's docstring gives the protocol, and needs only its own first line.
"""

import ast
import inspect
import re
from pathlib import Path

import pytest
import yaml

import magexp

PACKAGE = Path(magexp.__file__).resolve().parent
ROOT = PACKAGE.parent
#: every module (``_compiled.py`` and ``_version.py`` included: their helpers need a first line too)
MODULES = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def _estimator_classes() -> dict[str, set[str]]:
    """``{module path: class names}`` of every class a config of ``conf/estimator/`` names by ``_target_``."""
    found: dict[str, set[str]] = {}

    def walk(node):
        if isinstance(node, dict):
            target = node.get("_target_")
            if isinstance(target, str) and target.startswith("magexp."):
                module, _, name = target.rpartition(".")
                found.setdefault(module.removeprefix("magexp.").replace(".", "/") + ".py", set()).add(name)
            for value in node.values():
                walk(value)
    for path in sorted((ROOT / "conf" / "estimator").glob("*.yaml")):
        walk(yaml.safe_load(path.read_text()))
    return found


def _readers() -> dict[str, set[str]]:
    """``{module path: reader names}``: every public ``read`` or ``read_*`` function of the recording readers."""
    paths = [p for p in (PACKAGE / "core" / "readers").glob("*.py") if not p.name.startswith("_")]
    paths += [p for p in [PACKAGE / "core" / "text_readers.py"] if p.exists()]
    return {p.relative_to(PACKAGE).as_posix(): {n.name for n in ast.parse(p.read_text()).body
                                                if isinstance(n, ast.FunctionDef) and re.fullmatch(r"read(_\w+)?", n.name)}
            for p in paths}


def _public_api() -> dict[str, set[str]]:
    """:data:`PUBLIC`, worked out from the package, ``conf/estimator/`` and the readers' folder."""
    public = {"__init__.py": {"__getattr__"}, "calibration/api.py": {"calibrate"},
              "calibration/result.py": {"Calibration"}, "estimators/result.py": {"FitResult"},
              "estimators/base.py": {"Estimator"}, "problems/base.py": {"Problem", "LinearProblem", "CalibrationProblem"}}
    for extra in (_estimator_classes(), _readers()):
        for path, names in extra.items():
            public.setdefault(path, set()).update(names)
    return public


#: ``{module path: top-level names}`` of the public API (a class: with its public methods)
PUBLIC = _public_api()

#: protocol implementations (issue 42): functions that every module of a package defines with one
#: signature, documented once, in full, by the package's docstring (its sections "Parameters of ``name``"
#: and "Returns of ``name``"); an implementation needs only a first line saying what it does
PROTOCOLS = {"artifacts/kinds": ("table", "draw"), "core/readers": ("read", "claims", "sniff")}


def sections(doc: str) -> dict[str, list[str]]:
    """``{title: lines}`` of the numpydoc sections of ``doc`` (dedented): a title line underlined by dashes."""
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


def _public_functions(tree: ast.Module, names=None):
    """``(qualified name, node, class docstring)`` of every public function, method and constructor
    (properties aside: they are attributes; a dataclass's generated constructor has no node), of the
    top-level ``names`` only if given."""
    def visit(body, prefix="", owner=None):
        for node in body:
            if not prefix and names is not None and getattr(node, "name", None) not in names:
                continue
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                yield from visit(node.body, f"{prefix}{node.name}.", ast.get_docstring(node) or "")
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                public = (not node.name.startswith("_") or node.name in ("__getattr__", "__dir__", "__call__")
                          or (node.name == "__init__" and owner is not None))
                prop = any(getattr(d, "id", getattr(d, "attr", None)) in ("property", "cached_property")
                           for d in node.decorator_list)
                if public and not prop:
                    yield f"{prefix}{node.name}", node, owner
    yield from visit(tree.body)


def without_first_line(source: str) -> list[str]:
    """The functions and classes of ``source`` (at module or class level; dunder methods but ``__init__``
    and ``__call__`` aside) whose docstring has no first line."""
    out = []

    def visit(body, prefix=""):
        for node in body:
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            dunder = node.name.startswith("__") and node.name.endswith("__")
            if (not dunder or node.name in ("__init__", "__call__")) and not (ast.get_docstring(node) or "").strip():
                if not (node.name == "__init__" and prefix):  # a constructor: its class documents it
                    out.append(prefix + node.name)
            if isinstance(node, ast.ClassDef):
                visit(node.body, f"{prefix}{node.name}.")
    visit(ast.parse(source).body)
    return out


def type_only_entries(source: str) -> list[str]:
    """``"function: parameter"`` of each ``Parameters`` entry of ``source`` that gives a type and no description."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            lines = sections(ast.get_docstring(node) or "").get("Parameters", [])
            for i, line in enumerate(lines):
                described = i + 1 < len(lines) and lines[i + 1][:1].isspace() and lines[i + 1].strip()
                if line.strip() and not line[0].isspace() and not described:
                    out.append(f"{getattr(node, 'name', 'module')}: {line.split(' : ')[0]}")
    return out


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


def protocol_docs(path: Path) -> dict[str, str]:
    """``{name: numpydoc}`` of the protocol functions a module implements, from its package's docstring."""
    package = path.parent.relative_to(PACKAGE).as_posix()
    if package not in PROTOCOLS or path.name == "__init__.py":
        return {}
    found = sections(ast.get_docstring(ast.parse((path.parent / "__init__.py").read_text())))
    return {name: "\n".join(["Parameters", "----------", *found.get(f"Parameters of ``{name}``", []),
                             "Returns", "-------", *found.get(f"Returns of ``{name}``", [])])
            for name in PROTOCOLS[package]}


def missing_sections(source: str, protocol: dict[str, str] | None = None, names=None) -> list[str]:
    """``"name: what"`` of each public function of ``source`` (of its top-level ``names`` if given) lacking
    a section it needs, or a parameter its ``Parameters`` section does not name; a function of ``protocol``
    needs its own first line only, its sections are the protocol's (:func:`protocol_docs`)."""
    missing = []
    for name, node, owner in _public_functions(ast.parse(source), names):
        doc = ast.get_docstring(node) or ""
        if name in (protocol or {}):
            if not doc.strip():
                missing.append(f"{name}: first line")
            doc = protocol[name]
        wanted = _parameters(node)
        if name.endswith("__init__"):  # numpydoc: the class documents its constructor
            doc = owner + "\n\n" + doc if sections(doc).get("Parameters") is None else doc
        named = documented(doc)
        if wanted and not named:
            missing.append(f"{name}: Parameters")
        elif wanted and set(wanted) - named:
            missing.append(f"{name}: Parameters ({', '.join(p for p in wanted if p not in named)})")
        if _returns_value(node) and not name.endswith("__init__") and not re.search(
                r"^\s*(Returns|Yields)\n\s*-+$", doc, re.M):
            missing.append(f"{name}: Returns")
    return missing


def test_the_check_finds_what_is_missing():
    source = '''
def documented(x, *rest):
    """Twice.

    Parameters
    ----------
    x : float
        A number.
    *rest
        Ignored.

    Returns
    -------
    float
        ``2 x``.
    """
    return 2 * x


def bare(x):
    """Twice, undocumented."""
    return 2 * x


def half(x, y):
    """Half named.

    Parameters
    ----------
    x : float
    """
    print(x, y)


class Thing:
    """A thing.

    Parameters
    ----------
    size : int
        Its size.
    """

    def __init__(self, size, colour):
        self.size = size

    @property
    def area(self):
        """An attribute: no sections needed."""
        return 1

    def apply(self, y):
        """Nothing returned, a parameter undocumented."""
        print(y)


def _private(z):
    return z
'''
    assert missing_sections(source) == ["bare: Parameters", "bare: Returns", "half: Parameters (y)",
                                        "Thing.__init__: Parameters (colour)", "Thing.apply: Parameters"]


def test_a_protocol_implementation_needs_its_first_line_only():
    protocol = {"table": "Summary.\n\nParameters\n----------\nruns : ArtifactRuns\nplot : Plot\n\n"
                         "Returns\n-------\npandas.DataFrame\n"}
    source = '''
def table(runs, plot):
    """One row per cell."""
    return runs


def table_too(runs, plot):
    """Not in the protocol: full sections."""
    return runs
'''
    assert missing_sections(source, protocol) == ["table_too: Parameters", "table_too: Returns"]
    assert missing_sections(source.replace('"""One row per cell."""', "pass"), protocol)[0] == "table: first line"
    assert missing_sections(source.replace("table(runs, plot)", "table(runs, plot, extra)"), protocol)[0] \
        == "table: Parameters (extra)"  # the protocol must name what an implementation takes


def test_the_kinds_protocol_is_documented_by_its_package():
    docs = protocol_docs(PACKAGE / "artifacts" / "kinds" / "final.py")
    assert documented(docs["table"]) == {"runs", "plot"} and documented(docs["draw"]) == {"table", "spec", "axes"}
    assert all(sections(doc)["Returns"] for doc in docs.values())
    assert protocol_docs(PACKAGE / "artifacts" / "kinds" / "__init__.py") == {}


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


def test_the_first_line_and_type_only_checks_find_what_is_missing():
    source = '''
def helper(x):
    return x


class Box:
    """A box."""

    def __init__(self):
        pass

    def _inner(self):
        """"""

    def __len__(self):
        return 0


def listed(a, b):
    """Listed.

    Parameters
    ----------
    a : int
    b : float
        Described.
    """
'''
    assert without_first_line(source) == ["helper", "Box._inner"]
    assert type_only_entries(source) == ["listed: a"]


def test_the_public_api_is_found():
    if not (ROOT / "conf" / "estimator").is_dir():
        pytest.skip("no conf/estimator/ beside the package (a copy of magexp/ alone): the estimators' classes are unknown")
    assert PUBLIC["calibration/api.py"] == {"calibrate"} and "Calibration" in PUBLIC["calibration/result.py"]
    assert {"SwarmOptimizer"} <= PUBLIC["estimators/swarm.py"] and {"KalmanFilter"} <= PUBLIC["estimators/kalman.py"]
    assert {"Linear"} <= PUBLIC["estimators/schedules.py"]  # a strategy a config builds
    assert sum(len(names) for path, names in PUBLIC.items() if path.startswith("core/")) >= 6  # the readers
    for path, names in PUBLIC.items():
        defined = {getattr(n, "name", None) for n in ast.parse((PACKAGE / path).read_text()).body}
        assert names <= defined, f"{path}: {names - defined}"


@pytest.mark.parametrize("path", sorted(PUBLIC), ids=str)
def test_the_public_api_has_its_numpydoc_sections(path):
    module = PACKAGE / path
    assert missing_sections(module.read_text(), protocol_docs(module), PUBLIC[path]) == []


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.relative_to(PACKAGE).as_posix())
def test_every_function_and_class_has_a_first_line_and_no_bare_parameter(path):
    source = path.read_text()
    assert without_first_line(source) == []
    assert type_only_entries(source) == []
