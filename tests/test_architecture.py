"""Architecture rules: the numerical core imports no web package and never imports app/; no import
circle inside the core, app/ or app/explorer/; the core is imported by one name; outside
app/explorer/, only the server start-up imports the explorer."""

from __future__ import annotations

import ast
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
WEB = ("viser", "fastapi", "uvicorn", "starlette", "pydantic", "app", "websockets", "plotly")


def test_core_imports_no_web_package_at_run_time():
    code = (
        "import sys, pkgutil, importlib, paraspace.kinematics as k\n"
        "for m in pkgutil.iter_modules(k.__path__): importlib.import_module('paraspace.kinematics.' + m.name)\n"
        f"bad = sorted({{m.split('.')[0] for m in sys.modules}} & set({WEB!r}))\n"
        "bad += sorted(m for m in sys.modules if m.startswith('paraspace.app'))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert out.stdout.strip() == "", f"kinematics pulled in: {out.stdout}"


def test_core_source_never_names_a_web_package():
    for path in (ROOT / "kinematics").glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for name in names:
                assert name.split(".")[0] not in WEB, f"{path.name} imports {name}"
                assert not name.startswith("paraspace.app"), f"{path.name} imports {name}"


def _relative_imports(path: pathlib.Path, package: tuple[str, ...]) -> set[tuple[str, ...]]:
    """The modules ``path`` imports (at any depth of its code, deferred imports included), as
    dotted tuples relative to the repository's packages: ``("kinematics", "workspace")``."""
    out: set[tuple[str, ...]] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                mod = (*base, *node.module.split(".")) if node.module else base
                out.add(mod)
                out.update((*mod, a.name) for a in node.names)
            elif node.module and node.module.startswith("paraspace."):
                mod = tuple(node.module.split(".")[1:])
                out.add(mod)
                out.update((*mod, a.name) for a in node.names)
        elif isinstance(node, ast.Import):
            out.update(tuple(a.name.split(".")[1:]) for a in node.names if a.name.startswith("paraspace."))
    return out


def _module_graph(folder: str) -> dict[str, set[str]]:
    """Module -> the sibling modules it imports, for the flat package ``folder`` (``"app/explorer"``)."""
    package = tuple(folder.split("/"))
    names = {p.stem for p in (ROOT / folder).glob("*.py")}
    graph: dict[str, set[str]] = {}
    for name in names:
        deps = _relative_imports(ROOT / folder / f"{name}.py", package)
        n = len(package)
        graph[name] = {d[n] for d in deps if len(d) > n and d[:n] == package and d[n] in names} - {name}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_cycle_finder_finds_a_circle_and_only_circles():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set(), "c": {"a", "b"}}) == []


def test_no_import_circle_in_the_core():
    graph = _module_graph("kinematics")
    assert "bracket" in graph and "workspace" in graph["dexterous"]  # the graph sees the modules
    assert _cycles(graph) == [], "import circle in kinematics/"


def test_no_import_circle_in_the_explorer():
    graph = _module_graph("app/explorer")
    assert "session" in graph["server"]  # the graph sees the modules
    assert _cycles(graph) == [], "import circle in app/explorer/"


def test_no_import_circle_in_the_app():
    """app/'s own modules (the command line, its command modules, links, formats...): the circles
    cli <-> report_cli and urlstate <-> mechanism_link are gone (app/cli_flags.py, app/numfmt.py)."""
    graph = _module_graph("app")
    assert "cli_flags" in graph["report_cli"] and "numfmt" in graph["urlstate"]  # the graph sees the modules
    assert _cycles(graph) == [], "import circle in app/"


def test_the_core_is_imported_by_one_name_only():
    """Every file of the product, its tests, benchmarks and examples imports the core as
    ``paraspace.kinematics``, never as the checkout's top-level ``kinematics`` (a second copy of every
    module, compiled again; kinematics/numba_cache.py keeps their compiled kernels apart)."""
    offenders = []
    for folder in ("app", "kinematics", "paraspace", "tests", "benchmarks", "examples", "scripts"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                         [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                         else [])
                offenders += [f"{path.relative_to(ROOT)}:{node.lineno} imports {n}" for n in names
                              if n == "kinematics" or n.startswith("kinematics.")]
    assert offenders == []


def test_only_the_server_start_up_imports_the_explorer():
    allowed = {"serve.py"}
    offenders = []
    for path in sorted((ROOT / "app").rglob("*.py")):
        rel = path.relative_to(ROOT / "app")
        if rel.parts[0] == "explorer" or rel.name in allowed:
            continue
        package = ("app", *rel.parts[:-1])
        for mod in _relative_imports(path, package):
            if mod[:2] == ("app", "explorer"):
                offenders.append(f"{rel} imports {'.'.join(mod)}")
    assert offenders == []
