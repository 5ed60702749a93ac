"""numba's cache of the compiled kernels follows every source file of the package
(kinematics/numba_cache.py): a kernel whose callee in another module changed is compiled again,
where numba's own stamp (the kernel's file only) serves the former code."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

_RUN = r"""
import sys
from pathlib import Path
root = Path(sys.argv[1])
sys.path.insert(0, str(root))
if sys.argv[2] == "package":
    from paraspace.kinematics.numba_cache import install
    install(root / "pkg")
import pkg.a
print(pkg.a.kernel(1.0))
"""


def _run(root: Path, mode: str, cache: Path) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    proc = subprocess.run([sys.executable, str(root / "run.py"), str(root), mode], capture_output=True, text=True,
                          timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip()


@pytest.mark.parametrize("mode,after", [("package", "3.0"), ("numba", "2.0")])
def test_a_changed_callee_recompiles_its_callers(tmp_path, mode, after):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "b.py").write_text("from numba import njit\n\n\n@njit(cache=True)\ndef f(x):\n    return x + 1.0\n")
    (pkg / "a.py").write_text("from numba import njit\n\nfrom .b import f\n\n\n@njit(cache=True)\n"
                              "def kernel(x):\n    return f(x)\n")
    (tmp_path / "run.py").write_text(_RUN)
    cache = tmp_path / "cache"
    assert _run(tmp_path, mode, cache) == "2.0"
    (pkg / "b.py").write_text("from numba import njit\n\n\n@njit(cache=True)\ndef f(x):\n    return x + 2.0\n")
    # numba alone serves the kernel compiled with the former f (a.py did not change): the defect
    assert _run(tmp_path, mode, cache) == after


def test_the_cores_kernels_are_stamped_with_every_source_file():
    import hashlib

    from paraspace.kinematics import numba_cache
    from paraspace.kinematics.dexterity_neighbour import _neighbour_kernel

    package = Path(numba_cache.__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    locator = _neighbour_kernel._cache._impl.locator
    assert type(locator) in numba_cache.locators()
    assert locator.get_source_stamp()[1] == digest.hexdigest()


_RUN_AS = r"""
import sys
from pathlib import Path
top, mode, name = Path(sys.argv[1]), sys.argv[2], sys.argv[3]
sys.path.insert(0, str(top / "outer") if name == "pkg.k" else str(top))  # only this name is importable
if mode == "package":
    from paraspace.kinematics.numba_cache import install
    install(top / "outer" / "pkg")
import importlib
import numpy as np
print(importlib.import_module(name).kernel(np.arange(10.0)))
"""


@pytest.mark.parametrize("mode", ["package", "numba"])
def test_a_kernel_compiled_under_another_import_name_is_not_loaded(tmp_path, mode):
    """A module imported as ``pkg.k`` (its parent directory on sys.path, as ``kinematics.x`` from a
    checkout's root) and as ``outer.pkg.k`` by a process that cannot import ``pkg``: with numba's
    locators alone the second process loads the first one's entry, whose environment imports ``pkg``,
    and fails; the package's locators keep one entry per import name."""
    pkg = tmp_path / "outer" / "pkg"
    pkg.mkdir(parents=True)
    (tmp_path / "outer" / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("")
    (pkg / "k.py").write_text("from numba import njit, prange\n\n\n@njit(cache=True, parallel=True)\n"
                              "def kernel(x):\n    s = 0.0\n    for i in prange(x.shape[0]):\n        s += x[i]\n"
                              "    return s\n")
    (tmp_path / "run.py").write_text(_RUN_AS)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    runs = [subprocess.run([sys.executable, str(tmp_path / "run.py"), str(tmp_path), mode, name], capture_output=True,
                           text=True, timeout=300, env=env) for name in ("pkg.k", "outer.pkg.k")]
    assert runs[0].returncode == 0 and runs[0].stdout.strip() == "45.0", runs[0].stderr[-2000:]
    if mode == "numba":  # the defect the package's locators mend
        assert runs[1].returncode != 0 and "No module named 'pkg'" in runs[1].stderr, runs[1].stderr[-2000:]
    else:
        assert runs[1].returncode == 0 and runs[1].stdout.strip() == "45.0", runs[1].stderr[-2000:]
