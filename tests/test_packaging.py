"""Packaging: one installed namespace (`paraspace`), one version everywhere."""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import sys

import pytest

import paraspace

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_fresh_install_exposes_only_the_paraspace_namespace(tmp_path):
    """`pip install .` (here into a bare --target, no dependencies) puts exactly one top-level
    package into site-packages: paraspace, with kinematics, app and the static assets inside it."""
    # from a clean copy of the source: a stale build/ folder in the checkout would leak into the wheel
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".git", ".venv", "build", "dist", "*.egg-info",
                                                               "__pycache__", "test-artifacts", ".paraspace-cache"))
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                    "--target", str(target), str(src)], check=True, timeout=300)
    top = sorted(p.name for p in target.iterdir() if not p.name.endswith(".dist-info") and p.name != "bin")
    assert top == ["paraspace"], top
    pkg = target / "paraspace"
    for sub in ("kinematics", "app"):
        assert (pkg / sub / "__init__.py").is_file(), sub
    # every sub-package of the source (app/api/, ...) is installed too: pyproject lists them one by one
    for init in sorted([*ROOT.glob("app/**/__init__.py"), *ROOT.glob("kinematics/**/__init__.py")]):
        rel = init.relative_to(ROOT)
        assert (pkg / rel).is_file(), f"{rel} is not installed: add its package to pyproject.toml"
    assert (pkg / "static" / "index.html").is_file()
    assert (pkg / "py.typed").is_file()  # PEP 561 marker: type checkers read the package's annotations
    # the installed copy imports as itself (not from this checkout) and finds its own assets
    code = ("import paraspace, paraspace.kinematics as k, importlib.resources as r;"
            "print(paraspace.__file__); print(k.__file__);"
            "print(len(r.files('paraspace.static').joinpath('index.html').read_text()))")
    out = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True,
                         cwd=tmp_path, env={"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin"}, timeout=120)
    lines = out.stdout.split()
    assert lines[0].startswith(str(pkg)) and lines[1].startswith(str(pkg / "kinematics")), lines
    assert int(lines[2]) > 100


def test_public_api_reexports_the_core():
    from paraspace.kinematics import Design, compute_workspace

    assert paraspace.Design is Design
    assert paraspace.compute_workspace is compute_workspace
    assert callable(paraspace.sweep_1d) and callable(paraspace.orientation_workspace)
    with pytest.raises(AttributeError):
        paraspace.no_such_name  # noqa: B018


def test_version_is_stated_once_and_reported_by_the_cli():
    import importlib.metadata

    import tomllib

    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert importlib.metadata.version("paraspace") == declared == paraspace.__version__
    out = subprocess.run([sys.executable, "-m", "paraspace.app.cli", "--version"], capture_output=True,
                         text=True, check=True, cwd=ROOT, timeout=120)
    assert out.stdout.strip() == f"paraspace {declared}"


def test_python_m_paraspace_is_the_cli():
    out = subprocess.run([sys.executable, "-m", "paraspace", "--version"], capture_output=True,
                         text=True, check=True, cwd=ROOT, timeout=120)
    assert out.stdout.strip() == f"paraspace {paraspace.__version__}"
    usage = subprocess.run([sys.executable, "-m", "paraspace", "--help"], capture_output=True,
                           text=True, check=True, cwd=ROOT, timeout=120)
    assert usage.stdout.startswith("usage: paraspace ")


def test_api_and_explorer_report_the_same_version():
    import httpx

    from paraspace.app.api import create_api
    from paraspace.app.explorer import Explorer
    from paraspace.app.jobs import JobManager
    from paraspace.app.serve import start_api

    jobs = JobManager(max_workers=1)
    srv = start_api(create_api(jobs), "127.0.0.1", 0)
    try:
        assert httpx.get(f"{srv.url}/api/v1/health", timeout=10).json()["version"] == paraspace.__version__
    finally:
        jobs.shutdown()
        srv.stop()
    from explorer_client import FakeBrowser  # tests/ (pytest's prepend import mode)

    exp = Explorer("127.0.0.1", 0).start()
    try:
        b = FakeBrowser(exp)
        assert f"paraspace {paraspace.__version__} " in b.session.panels.version.content
        b.close()
    finally:
        exp.stop()
