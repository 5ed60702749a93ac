#!/usr/bin/env bash
# Install paraspace into ./.venv and run the explorer (and REST API) on the paper's default design.
# Extra arguments go to `paraspace serve` (e.g. --port 9000 --host 0.0.0.0).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q .
exec .venv/bin/paraspace serve "$@"
