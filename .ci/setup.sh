#!/usr/bin/env bash
# Set up everything rbm_nb needs on a fresh machine that has only Python 3.11.
#   bash .ci/setup.sh demo   -> .venv with rbm_nb[all] (+ JupyterLab for the demo)
#   bash .ci/setup.sh test   -> the same plus the test tools and Debian's chromium
# Idempotent: a second run only checks that everything is there.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-demo}

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

if [ "$mode" = test ] && [ ! -x /usr/bin/chromium ]; then
  echo "setup: installing Debian's chromium for the browser tests"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq chromium >/dev/null
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv with $($PY --version)"
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
if [ "$mode" = test ]; then extras="all,lab,dev"; else extras="all,lab"; fi
echo "setup: installing rbm_nb[$extras] (pinned by .ci/constraints.txt)"
.venv/bin/python -m pip install -q -c .ci/constraints.txt -e ".[$extras]"

# Compile every numba kernel into the on-disk cache now, so that neither the
# demo's first cell nor the first tests wait for compilation.
echo "setup: warming numba's cache"
.venv/bin/python -m rbm_nb._warmup
