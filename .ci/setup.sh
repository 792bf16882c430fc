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
  # --compile-bytecode for the tests: the suite imports most of what is
  # installed, and its own time must not include writing .pyc files. Not for
  # the demo: it imports a small part of it (Python writes those .pyc on
  # first import), and compiling all of it was the set-up's largest cost
  # (measured on a fresh clone under load: 125 s wall, 36 s CPU, against 12 s
  # for the same install without it)
  local bytecode=()
  [ "$mode" = test ] && bytecode=(--compile-bytecode)
  .venv/bin/uv pip install --quiet --python .venv/bin/python "${bytecode[@]}" \
    -c .ci/constraints.txt -e ".[$1]"
}

# numba's kernels into their on-disk cache, so that neither the demo's
# notebook nor the tests compile them. A fresh clone compiles 88 kernel
# signatures (about 5 min of one core; fused.lookup_chain alone ~45 s), so
# the compile starts as soon as numba is installed -- a small first uv run --
# and runs during the main install, one worker process per core, the
# explorer's kernels first (rbm_nb/_kernels/_warmup.py). The demo returns when the
# install is done and leaves the compile running in the background (at low
# priority once the explorer's kernels are ready); the tests wait for all
# of them (a test must not wait for a compile). A process that needs a
# signature a worker is compiling waits for it and loads it: nothing
# compiles twice.
cache_dir=${NUMBA_CACHE_DIR:-rbm_nb/_kernels/__pycache__}
warm_stamp=".venv/.rbm_nb-warm"
# kept saying "N M": N of the M kernel signatures ready
warm_status=".venv/.rbm_nb-warm-status"
warm_pids=".venv/.rbm_nb-warm-pid"
warm_log=".venv/rbm_nb-warm-up.log"
warm_sources=""
started=""
workers_alive() {
  local pid
  for pid in $(cat "$warm_pids" 2>/dev/null); do
    kill -0 "$pid" 2>/dev/null && return 0
  done
  return 1
}
# a failed set-up must not leave the workers running behind the script
trap 'if [ -n "$started" ]; then kill $(cat "$warm_pids" 2>/dev/null) 2>/dev/null || true; fi' EXIT
sources() { (echo "$cache_dir"; find rbm_nb -name '*.py' -printf '%p %T@ %s\n' | sort) | sha256sum; }
start_warm_up() {  # start the workers unless the cache is warm or they run
  warm_sources=$(sources)
  if [ "$(cat "$warm_stamp" 2>/dev/null)" = "$warm_sources" ] &&
     [ -n "$(find "$cache_dir" -name '*.nbc' -print -quit 2>/dev/null)" ]; then
    say "numba's cache is warm (no file of rbm_nb/ changed since the last warm-up)"
    warm_sources=""
    return
  fi
  rm -f "$warm_stamp"
  if workers_alive; then
    say "the kernel compile of an earlier set-up is still running: waiting for it"
    return
  fi
  if ! .venv/bin/python -c "import numba" 2>/dev/null; then
    say "installing numba first (the kernels compile during the main install)"
    .venv/bin/uv pip install --quiet --python .venv/bin/python --compile-bytecode \
      -c .ci/constraints.txt numba numpy llvmlite
  fi
  local background=""
  [ "$mode" = demo ] && background="--background"
  say "compiling the numba kernels into their cache, the explorer's first, one process per core"
  # the source tree itself: rbm_nb is not installed yet (the editable install
  # points at the same files, so the cache serves it)
  PYTHONPATH=$PWD .venv/bin/python -P -m rbm_nb._kernels._warmup --start $background \
    --pids "$warm_pids" --log "$warm_log"
  started=1
}
finish_warm_up() {  # demo: say how far it is; test: wait for every kernel
  [ -n "$warm_sources" ] || return 0
  local how=(--wait all)
  if [ "$mode" = demo ]; then
    how=(--report)
  else
    say "waiting for the kernels to compile (a test must not wait for one)"
  fi
  if ! PYTHONPATH=$PWD .venv/bin/python -P -m rbm_nb._kernels._warmup "${how[@]}" \
      --pids "$warm_pids" --status "$warm_status" |
      while IFS= read -r line; do say "$line"; done; then
    cat "$warm_log" >&2
    exit 1
  fi
  started=""  # from here on the workers are meant to run (demo) or are done
  read -r n m < "$warm_status" 2>/dev/null || { n=0; m=1; }
  if [ "$n" = "$m" ]; then
    echo "$warm_sources" > "$warm_stamp"
  fi
}

# what the install depends on; unchanged -> nothing to do
stamp=".venv/.rbm_nb-install-$mode"
want=$(cat pyproject.toml setup.py .ci/constraints.txt <(echo "$extras") | sha256sum)
if [ "$(cat "$stamp" 2>/dev/null)" = "$want" ] && .venv/bin/python -c "import rbm_nb" 2>/dev/null; then
  say "rbm_nb[$extras] already installed with the pins of .ci/constraints.txt"
  start_warm_up
else
  rm -f "$stamp"
  start_warm_up
  say "installing rbm_nb[$extras] (editable) with the pins of .ci/constraints.txt"
  install "$extras"
  echo "$want" > "$stamp"
  say "installed"
fi
finish_warm_up

if [ -n "$apt_pid" ]; then
  say "waiting for apt (chromium)"
  if ! wait "$apt_pid"; then
    cat .venv/apt.log >&2
    exit 1
  fi
fi
if [ -n "$warm_sources" ]; then
  read -r n m < "$warm_status" 2>/dev/null || { n="?"; m="?"; }
  if [ "$n" = "$m" ]; then
    say "done: $n of $m kernel signatures ready"
  else
    say "done: $n of $m kernel signatures ready, the rest compiling in the background ($warm_log)"
  fi
else
  say "done"
fi
