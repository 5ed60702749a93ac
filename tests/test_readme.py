"""The README's "Python API" example runs as written (in a scratch directory)."""

from __future__ import annotations

import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_python_api_example_runs(tmp_path):
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Python API"):]
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    script = tmp_path / "example.py"
    script.write_text(block)
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "MPLCONFIGDIR": str(tmp_path / "mpl")}
    out = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                         env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.splitlines()
    assert lines[0].startswith("V = ") and "voxels" in lines[0]
    assert lines[1].startswith("boundary complete:")
    vols = [float(line.split()[1]) for line in lines[2:5]]
    assert [float(line.split()[0]) for line in lines[2:5]] == [30.0, 50.0, 70.0]
    assert vols[0] < vols[1] < vols[2]  # more leg stroke, more workspace
    mesh = (tmp_path / "workspace.stl").read_bytes()
    assert len(mesh) > 84  # a binary STL with faces
