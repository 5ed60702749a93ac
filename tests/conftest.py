"""Suite-wide set-up: compile every kernel a request can reach once, before any test runs
(kinematics/warmup.py), so that no request in a test waits on a numba compile however busy the
machine is (the kernels' on-disk cache then serves the CLI subprocesses too)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session", autouse=True)
def warm_kernels() -> None:
    from paraspace.kinematics.warmup import warm_up

    warm_up()
