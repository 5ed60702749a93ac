"""Concurrent jobs are safe under numba's workqueue threading layer (used when libgomp/TBB are
missing, e.g. in slim containers), which aborts the process on concurrent parallel launches."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]

SCRIPT = """
import threading
import numba
from paraspace.kinematics.design import Design
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace, reachable
import numpy as np

errors = []
def run(a):
    try:
        for _ in range(4):
            res = compute_workspace(Design(a=a), WorkspaceSettings(voxel=4.0))
            measure_workspace(res)
            reachable(Design(a=a), np.zeros((50, 3)) + [0, 0, 130])
    except Exception as exc:  # pragma: no cover - reported below
        errors.append(repr(exc))
threads = [threading.Thread(target=run, args=(a,)) for a in (40, 50, 60, 70)]
[t.start() for t in threads]
[t.join() for t in threads]
print(numba.threading_layer(), len(errors))
"""


def test_concurrent_kernels_under_workqueue_layer():
    env = dict(os.environ, NUMBA_THREADING_LAYER="workqueue")
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, cwd=ROOT, env=env,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["workqueue", "0"]
