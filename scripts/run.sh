#!/usr/bin/env bash
# Install paraspace into ./.venv and run the explorer (and REST API) on the paper's default design.
# Extra arguments go to `paraspace serve` (e.g. --port 9000 --host 0.0.0.0).
# One line per step; the install is skipped when neither pyproject.toml nor a source file changed
# since the last one (the fingerprint is kept in .venv/.paraspace-installed).
set -euo pipefail
cd "$(dirname "$0")/.."
fingerprint() {
  find pyproject.toml paraspace kinematics app static -type f \( -name '*.py' -o -name '*.html' -o -name '*.toml' -o -name '*.typed' \) \
    -not -path '*/__pycache__/*' -print0 | LC_ALL=C sort -z | xargs -0 sha256sum | sha256sum | cut -d' ' -f1
}
if [ ! -x .venv/bin/python ]; then
  echo "[1/3] creating the virtual environment ./.venv"
  python3 -m venv .venv
else
  echo "[1/3] using the virtual environment ./.venv"
fi
want="$(fingerprint)"
if [ -x .venv/bin/paraspace ] && [ "$(cat .venv/.paraspace-installed 2>/dev/null)" = "$want" ]; then
  echo "[2/3] paraspace is installed and up to date (no source changed): install skipped"
else
  echo "[2/3] installing paraspace and its dependencies into ./.venv (a few minutes the first time)"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q .
  echo "$want" > .venv/.paraspace-installed
fi
echo "[3/3] starting the explorer (the first start compiles the numerical kernels: about 3 minutes on 2 cores; the first workspace waits for its own, about 2 minutes)"
exec .venv/bin/paraspace serve "$@"
