#!/usr/bin/env bash
# Set up everything rbm_nb needs on a fresh machine that has only Python 3.11.
#   bash .ci/setup.sh demo   -> .venv with rbm_nb[all,lab]
#   bash .ci/setup.sh test   -> the same plus dev and docs tools and Debian's chromium
# Idempotent and quick the second time: the install is skipped while pyproject.toml,
# setup.py, .ci/constraints.txt and the mode are unchanged, and the numba warm-up
# while no file of rbm_nb/ changed (numba's cache is keyed on the files' mtimes).
#
# uv (from PyPI, bootstrapped into .venv with the interpreter's own pip) creates
# nothing else and installs every package at the exact pin of .ci/constraints.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-demo}
case "$mode" in
  demo) extras="all,lab" ;;
  test) extras="all,lab,dev,docs" ;;
  *) echo "usage: bash .ci/setup.sh [demo|test]" >&2; exit 2 ;;
esac
start=$SECONDS
say() { echo "setup [$((SECONDS - start)) s]: $*"; }
as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

PY=${PYTHON:-python3}
UV_VERSION=$(sed -n 's/^uv==//p' .ci/constraints.txt)
# The interpreter's own pip installs uv into the venv (pip >= 22.3 can target
# another environment), which spares ensurepip's copy of pip in .venv; without a
# pip beside the interpreter, the venv gets one.
if "$PY" -m pip --version >/dev/null 2>&1; then
  pip=("$PY" -m pip --python .venv/bin/python); venv_opts=(--without-pip)
else
  pip=(.venv/bin/python -m pip); venv_opts=()
fi
if [ ! -x .venv/bin/python ]; then
  say "creating .venv with $("$PY" --version)"
  "$PY" -m venv "${venv_opts[@]}" .venv
fi

# Debian's chromium for the browser tests: apt works while uv installs.
apt_pid=""
if [ "$mode" = test ] && [ ! -x /usr/bin/chromium ]; then
  say "installing Debian's chromium for the browser tests (in the background)"
  ( as_root apt-get update -qq &&
    DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq chromium >/dev/null
  ) > .venv/apt.log 2>&1 &
  apt_pid=$!
fi
if [ "$(.venv/bin/uv --version 2>/dev/null | cut -d' ' -f2)" != "$UV_VERSION" ]; then
  say "bootstrapping uv $UV_VERSION from PyPI into .venv"
  "${pip[@]}" install -q --disable-pip-version-check "uv==$UV_VERSION"
fi

install() {  # install rbm_nb[$1] (editable) at the exact pins
  # --compile-bytecode: later imports (the warm-up, JupyterLab) skip writing .pyc
  .venv/bin/uv pip install --quiet --python .venv/bin/python --compile-bytecode \
    -c .ci/constraints.txt -e ".[$1]"
}

# Compile every numba kernel into the on-disk cache, so that neither the
# demo's first cell nor the first tests wait for compilation. numba writes one
# .nbc file per compiled signature: their count is the progress shown. (Starting
# it before JupyterLab & co. are installed, to overlap the two, was measured:
# two uv runs cost more than the overlap saved.)
cache_dir=${NUMBA_CACHE_DIR:-rbm_nb/_kernels/__pycache__}
warm_stamp=".venv/.rbm_nb-warm"
# the warm-up keeps this file saying "N M": N of its M kernel signatures ready
warm_status=".venv/.rbm_nb-warm-status"
warm_pid=""
# a failed install must not leave the warm-up running behind the script
trap 'if [ -n "$warm_pid" ]; then kill "$warm_pid" 2>/dev/null || true; fi' EXIT
warm_sources=""
warm_up() {
  local sources
  sources=$( (echo "$cache_dir"; find rbm_nb -name '*.py' -printf '%p %T@ %s\n' | sort) | sha256sum)
  if [ "$(cat "$warm_stamp" 2>/dev/null)" = "$sources" ] &&
     [ -n "$(find "$cache_dir" -name '*.nbc' -print -quit 2>/dev/null)" ]; then
    say "numba's cache is warm (no file of rbm_nb/ changed since the last warm-up)"
    return
  fi
  say "compiling the numba kernels into their cache, one process per core (about 5 minutes on 2 cores the first time)"
  rm -f "$warm_stamp"
  rm -f "$warm_status"
  .venv/bin/python -m rbm_nb._warmup --status "$warm_status" &
  warm_pid=$!
  warm_sources=$sources
}

# what the install depends on; unchanged -> nothing to do
stamp=".venv/.rbm_nb-install-$mode"
want=$(cat pyproject.toml setup.py .ci/constraints.txt <(echo "$extras") | sha256sum)
if [ "$(cat "$stamp" 2>/dev/null)" = "$want" ] && .venv/bin/python -c "import rbm_nb" 2>/dev/null; then
  say "rbm_nb[$extras] already installed with the pins of .ci/constraints.txt"
  warm_up
else
  rm -f "$stamp"
  say "installing rbm_nb[$extras] (editable) with the pins of .ci/constraints.txt"
  install "$extras"
  echo "$want" > "$stamp"
  say "installed"
  warm_up
fi

if [ -n "$warm_pid" ]; then
  ticks=0
  while kill -0 "$warm_pid" 2>/dev/null; do
    sleep 1
    ticks=$((ticks + 1))
    if [ $((ticks % 15)) = 0 ] && kill -0 "$warm_pid" 2>/dev/null; then
      read -r n m < "$warm_status" 2>/dev/null || { n="?"; m="?"; }
      say "  still compiling: $n of $m kernel signatures ready"
    fi
  done
  pid=$warm_pid
  warm_pid=""  # reaped below: nothing for the trap to kill
  wait "$pid"
  echo "$warm_sources" > "$warm_stamp"
fi

if [ -n "$apt_pid" ]; then
  say "waiting for apt (chromium)"
  if ! wait "$apt_pid"; then
    cat .venv/apt.log >&2
    exit 1
  fi
fi
say "done"
