"""The functions ``paraspace`` re-exports are documented in numpydoc form (``Parameters``, ``Returns``,
``Examples``) and their examples run as doctests (coarse voxels: seconds)."""

from __future__ import annotations

import doctest
import inspect

import pytest

import paraspace

FUNCTIONS = sorted(n for n in paraspace.__all__ if inspect.isfunction(getattr(paraspace, n, None)))


def test_the_public_functions_are_found():
    assert {"compute_workspace", "reachable", "measure_workspace", "sweep_1d", "mobility"} <= set(FUNCTIONS)


@pytest.mark.parametrize("name", FUNCTIONS)
def test_numpydoc_sections(name: str) -> None:
    doc = inspect.getdoc(getattr(paraspace, name)) or ""
    for section in ("Parameters", "Returns", "Examples"):
        assert f"\n{section}\n{'-' * len(section)}\n" in doc, f"{name}: no {section} section"
    params = [p for p in inspect.signature(getattr(paraspace, name)).parameters]
    listed = doc.split("\nParameters\n")[1].split("\nReturns\n")[0]
    for p in params:  # every parameter is described (``a, b : type`` lines count for both)
        assert any(line.split(" : ")[0].replace(" ", "").split(",").count(p)
                   for line in listed.splitlines() if " : " in line), f"{name}: parameter {p} undocumented"


@pytest.mark.parametrize("name", FUNCTIONS)
def test_examples_run(name: str) -> None:
    tests = doctest.DocTestFinder(recurse=False).find(getattr(paraspace, name), name, globs={})
    assert tests and tests[0].examples, f"{name}: no doctest example"
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    for t in tests:
        runner.run(t, out=report.append)
    assert runner.failures == 0, "".join(report)
