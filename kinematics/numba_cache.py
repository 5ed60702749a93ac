"""numba's on-disk cache of the compiled kernels, valid only for the sources they were compiled from.

Definition. A kernel of this package compiled with ``cache=True`` is taken from numba's cache only
when its *source stamp* equals the one stored beside it, and the stamp here is the pair

    (numba's own stamp of the kernel's file,  SHA-256 of every ``.py`` file of the package)

(:func:`package_stamp`: each file's path relative to the package and its bytes, in sorted order).
Any change to any source file of the package therefore recompiles every kernel on first use.

Why: numba stamps only the file that defines a function. A kernel that calls, or inlines, a function
of another module keeps its compiled code when only that other module changed -- after a ``git
pull`` of a checkout, an editable install, or a patch -- and the former code runs, silently (seen
here: the dexterity field's kernel kept the former eigenvalue step of ``dexterity_sweep`` after that
module changed). A pip upgrade rewrites every file, so it was safe; a checkout was not.

:func:`install` puts the package's locators ahead of numba's own (for the files under the package's
directory only; every other function keeps numba's behaviour). Importing this module installs them;
``kinematics/__init__.py`` imports it before any kernel module, since numba picks a function's
locator when the function is decorated.

Import names. A checkout's modules can be imported under two names: ``paraspace.kinematics.x`` (the
installed namespace) and ``kinematics.x`` (the checkout's root on ``sys.path``, e.g. a script or
a test run from it). numba names a cache file by the source file alone, so both names shared one
entry, and a kernel compiled under one name stores an environment that imports that name when it is
loaded: a process without the checkout's root on ``sys.path`` then failed with "No module named
'kinematics'" on a kernel another process had compiled (seen: the explorer's dexterity colours after
a test run). The cache file's name here also carries a hash of the module's import name, so each
name has its own entries.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path
from typing import Any

from numba.core import caching

__all__ = ["install", "package_stamp", "locators"]

#: The directory of this package (the numerical core).
PACKAGE = Path(__file__).resolve().parent


@functools.cache
def package_stamp(package: Path = PACKAGE) -> str:
    """SHA-256 (hex) of every ``.py`` file under ``package``: relative path and bytes, sorted."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


def locators(package: Path = PACKAGE) -> tuple[type, ...]:
    """numba's source-file locators (a cache directory the user named, ``__pycache__`` beside the
    file, the user-wide directory) for the functions defined under ``package``, stamped with
    :func:`package_stamp` as well (module docstring); the same classes for the same directory."""
    return _locators(Path(package).resolve())


class _PackageStamped:
    """Mixin over one of numba's source-file locators: it claims only the functions defined under
    ``_root``, stamps them with :func:`package_stamp` of ``_root`` as well, and keeps each import name
    of a module in cache files of its own."""

    _root: Path
    _import_name: str = ""

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> Any:
        try:
            inside = Path(py_file).resolve().is_relative_to(cls._root)
        except (OSError, ValueError):
            inside = False
        if not inside:
            return None
        self = super().from_function(py_func, py_file)  # type: ignore[misc]
        if self is not None:
            self._import_name = str(getattr(py_func, "__module__", "") or "")
        return self

    def get_source_stamp(self) -> Any:
        return (super().get_source_stamp(), package_stamp(self._root))  # type: ignore[misc]

    def get_disambiguator(self) -> str:
        # numba names a cache file by the file's base name, the function and its line; the module's
        # import name goes in too (module docstring, "Import names")
        tag = hashlib.sha256(self._import_name.encode()).hexdigest()[:8]
        return f"{super().get_disambiguator()}-{tag}"  # type: ignore[misc]


@functools.cache
def _locators(root: Path) -> tuple[type, ...]:
    return tuple(type("Package" + base.__name__, (_PackageStamped, base), {"_root": root})
                 for base in _numba_locators())


def _numba_locators() -> tuple[type, ...]:
    """numba's source-file locators (public names since numba 0.62, underscored before)."""
    names = ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator")
    return tuple(getattr(caching, n, None) or getattr(caching, "_" + n) for n in names)


def install(package: Path = PACKAGE) -> None:
    """Put :func:`locators` of ``package`` first in numba's list (idempotent)."""
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    classes = impl._locator_classes
    for cls in reversed(locators(package)):
        if cls not in classes:
            classes.insert(0, cls)


install()
