#!/usr/bin/env bash
# Install everything the tests need, lint, type-check and run the whole suite:
#  - Debian's chromium (the browser test drives it through Playwright; `playwright install` cannot
#    download here) and g++ (tests/test_cuda_dense.py compiles the CUDA backend's device functions
#    for the CPU), with apt-get (as root, or through sudo);
#  - ./.venv with the project and its test extras;
#  - ruff and mypy (configured in pyproject.toml) on the package: zero findings, or the run stops;
#  - the doctests of the public functions and the suite (tests/, examples/ run by tests/test_examples.py).
#    The suite runs on two worker processes (pytest-xdist, a test file each at a time: a file's
#    module-scoped servers stay in one process; the longest files first, tests/conftest.py's
#    LONGEST_FIRST); `-n 0` among the extra arguments runs it in one.
# Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x /usr/bin/chromium ] || ! command -v g++ >/dev/null; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium g++ >/dev/null
fi
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q ".[test]"
.venv/bin/python -m ruff check kinematics app paraspace examples
.venv/bin/python -m mypy
exec .venv/bin/python -m pytest -ra -n 2 --dist loadfile --no-loadscope-reorder "$@"
