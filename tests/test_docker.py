"""The Dockerfile, checked without a Docker engine: its instructions are parsed and verified, and its
entrypoint command is run in the current environment on free loopback ports (the only change:
``--host 0.0.0.0`` becomes ``127.0.0.1`` because tests bind loopback only, and the ports are free
ones); both ports must answer, the image's HEALTHCHECK command must pass against it, and SIGTERM
(``docker stop``) must end it cleanly."""

from __future__ import annotations

import json
import os
import pathlib
import re
import shlex
import signal
import subprocess
import sys
import time

import httpx
import pytest

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "Dockerfile"


def _instructions() -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) pairs with line continuations joined and comments dropped."""
    out: list[tuple[str, str]] = []
    buf = ""
    for raw in DOCKERFILE.read_text().splitlines():
        line = raw.strip()
        if not buf and (not line or line.startswith("#")):
            continue
        if line.startswith("#"):
            continue
        if line.endswith("\\"):
            buf += line[:-1] + " "
            continue
        buf += line
        word, _, rest = buf.strip().partition(" ")
        out.append((word.upper(), rest.strip()))
        buf = ""
    return out


def _one(instr: list[tuple[str, str]], name: str) -> str:
    found = [a for w, a in instr if w == name]
    assert len(found) == 1, f"expected one {name}, found {found}"
    return found[0]


def _exec_form(args: str) -> list[str]:
    val = json.loads(args)
    assert isinstance(val, list) and all(isinstance(x, str) for x in val), args
    return val


def _pins(instr: list[tuple[str, str]]) -> dict[str, str]:
    text = " ".join(a for w, a in instr if w == "RUN" and "constraints.txt" in a)
    return {m.group(1).lower(): m.group(2) for m in re.finditer(r"([A-Za-z0-9_.\-]+)==([A-Za-z0-9_.+\-]+)", text)}


def test_base_user_ports_entrypoint():
    instr = _instructions()
    base = _one(instr, "FROM")
    assert re.fullmatch(r"python:3\.11-slim@sha256:[0-9a-f]{64}", base), f"the base image is pinned by digest: {base}"
    users = [(i, a) for i, (w, a) in enumerate(instr) if w == "USER"]
    assert users, "the image must switch to a non-root USER"
    last_user = users[-1][1]
    assert last_user not in ("root", "0", "0:0") and not last_user.startswith("root:")
    entry_i = [i for i, (w, _) in enumerate(instr) if w == "ENTRYPOINT"][0]
    assert users[-1][0] < entry_i
    assert set(_one(instr, "EXPOSE").split()) == {"8080", "8081"}
    entry = _exec_form(_one(instr, "ENTRYPOINT"))
    assert entry == ["paraspace", "serve", "--host", "0.0.0.0", "--port", "8080", "--api-port", "8081"]
    # the console script exists
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts.get("paraspace") == "paraspace.app.cli:main"


def test_healthcheck_targets_the_api_health_endpoint():
    from paraspace.app.api import API_PREFIX

    hc = _one(_instructions(), "HEALTHCHECK")
    assert "CMD" in hc
    assert f"http://127.0.0.1:8081{API_PREFIX}/health" in hc
    assert "timeout=" in hc


def test_install_is_the_readme_install_from_registries_only():
    instr = _instructions()
    runs = [a for w, a in instr if w == "RUN"]
    installs = [m.group(0).strip() for a in runs for m in re.finditer(r"pip install[^&|;]*", a)]
    # the dependencies, each checked against its hash, then the project as `pip install .` (with the
    # hash-checked build backend instead of one fetched for an isolated build)
    assert installs == ["pip install --require-hashes --no-deps -r /opt/paraspace/requirements.lock",
                        "pip install --no-build-isolation ."], installs
    # the same command as the documented / scripted install of the project for running it
    run_sh = (ROOT / "scripts" / "run.sh").read_text()
    assert re.search(r"pip install (-q )?\.\s*$", run_sh, re.M), "scripts/run.sh installs the project with `pip install .`"
    readme = ROOT / "README.md"
    if readme.exists():
        text = readme.read_text()
        # README shows `pip install .` or the script that runs it
        assert "pip install ." in text or "scripts/run.sh" in text, "README documents the install"
    # nothing is fetched from anywhere but the package registries
    text = DOCKERFILE.read_text()
    for bad in ("curl ", "wget ", "git clone", "ADD http", "npm ", "playwright install"):
        assert bad not in text, bad
    assert not any(w == "ADD" for w, _ in instr)


def test_dependencies_are_pinned_and_satisfy_pyproject():
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name

    instr = _instructions()
    env = " ".join(a for w, a in instr if w == "ENV")
    assert "PIP_CONSTRAINT=/opt/paraspace/constraints.txt" in env
    pins = {canonicalize_name(k): v for k, v in _pins(instr).items()}
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    missing, unsatisfied = [], []
    for d in deps:
        req = Requirement(d)
        name = canonicalize_name(req.name)
        if name not in pins:
            missing.append(req.name)
        elif req.specifier and not req.specifier.contains(pins[name], prereleases=True):
            unsatisfied.append(f"{req.name}: pinned {pins[name]}, pyproject wants {req.specifier}")
    assert not missing, f"not pinned in the Dockerfile: {missing}"
    assert not unsatisfied, unsatisfied
    # report (not assert) where the pins differ from the environment these tests run in
    import importlib.metadata as md

    drift = []
    for name, ver in sorted(pins.items()):
        try:
            have = md.version(name)
        except md.PackageNotFoundError:
            continue
        if have != ver:
            drift.append(f"{name} {ver} (here {have})")
    print("\npins differing from this environment:", ", ".join(drift) or "none")


def test_numba_cache_writable_and_context_small():
    instr = _instructions()
    env = " ".join(a for w, a in instr if w == "ENV")
    m = re.search(r"NUMBA_CACHE_DIR=(\S+)", env)
    assert m, "NUMBA_CACHE_DIR is set"
    cache = m.group(1)
    user = [a for w, a in instr if w == "USER"][-1]
    assert any(cache in a and "chown" in a and user in a for w, a in instr if w == "RUN"), \
        "the numba cache directory is created and owned by the runtime user"
    ignore = (ROOT / ".dockerignore").read_text().split()
    for pat in (".git", ".venv"):
        assert pat in ignore
    for needed in ("pyproject.toml", "README.md", "paraspace", "app", "kinematics", "static"):
        assert needed not in ignore


@pytest.mark.slow
def test_entrypoint_runs_and_both_ports_answer(tmp_path):
    from paraspace.app.serve import free_port

    entry = _exec_form(_one(_instructions(), "ENTRYPOINT"))
    port, api_port = free_port(), free_port()
    while api_port == port:
        api_port = free_port()
    cmd = list(entry)
    cmd[cmd.index("--host") + 1] = "127.0.0.1"  # tests bind loopback only (the image binds 0.0.0.0)
    cmd[cmd.index("--port") + 1] = str(port)
    cmd[cmd.index("--api-port") + 1] = str(api_port)
    exe = pathlib.Path(sys.executable).parent / cmd[0]
    assert exe.exists(), f"{exe}: install the project (pip install .) to get the console script"
    cmd[0] = str(exe)
    env = dict(os.environ, MPLCONFIGDIR=str(tmp_path / "mpl"))
    print("\nrunning:", shlex.join(cmd))
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    try:
        api_ok = viser_ok = False
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (api_ok and viser_ok):
            assert proc.poll() is None, proc.stdout.read() if proc.stdout else ""
            try:
                api_ok = api_ok or httpx.get(f"http://127.0.0.1:{api_port}/api/v1/health", timeout=2).status_code == 200
                viser_ok = viser_ok or httpx.get(f"http://127.0.0.1:{port}/", timeout=2).status_code == 200
            except httpx.HTTPError:
                pass
            time.sleep(0.1)
        print(f"both ports answered after {time.perf_counter() - t0:.2f} s")
        assert api_ok and viser_ok
        page = httpx.get(f"http://127.0.0.1:{port}/", timeout=5).text
        assert "<html" in page.lower()
        # the image's HEALTHCHECK command, pointed at this API port, passes
        hc = _one(_instructions(), "HEALTHCHECK")
        hc_cmd = _exec_form(hc[hc.index("CMD") + 3:].strip())
        hc_cmd = [c.replace("127.0.0.1:8081", f"127.0.0.1:{api_port}") for c in hc_cmd]
        hc_cmd[0] = sys.executable
        assert subprocess.run(hc_cmd, timeout=20).returncode == 0
        # docker stop: SIGTERM ends both servers cleanly
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=20)
        print(out[-2000:])
        assert proc.returncode == 0, out
        assert f"127.0.0.1:{api_port}" in out and f":{port}" in out  # both URLs were printed
        with pytest.raises(httpx.HTTPError):
            httpx.get(f"http://127.0.0.1:{api_port}/api/v1/health", timeout=2)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)


def test_every_pinned_dependency_is_installed_by_hash():
    """requirements.lock holds exactly the Dockerfile's pins (plus the build backend), each with a
    sha256, and satisfies pyproject's build requirement."""
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name

    lock = (ROOT / "requirements.lock").read_text()
    entries = re.findall(r"^([A-Za-z0-9_.\-]+)==(\S+) \\\n\s+--hash=sha256:([0-9a-f]{64})$", lock, re.M)
    locked = {canonicalize_name(n): v for n, v, _ in entries}
    assert len(entries) == len(re.findall(r"^[A-Za-z0-9_.\-]+==", lock, re.M)), "every entry has its hash"
    pins = {canonicalize_name(k): v for k, v in _pins(_instructions()).items()}
    assert {k: locked.get(k) for k in pins} == pins, "the lock installs the pinned versions"
    backend = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    for req in map(Requirement, backend):
        assert req.specifier.contains(locked[canonicalize_name(req.name)]), f"{req} is in the lock"
