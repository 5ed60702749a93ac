"""Architecture rules: the numerical core imports no web package and never imports app/."""

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
