#!/usr/bin/env bash
# How long the README's demo command takes to be ready, fresh and a second time.
#   bash .ci/measure_setup.sh [workdir]
# Fresh: a new clone of this repository's HEAD in workdir (default: a temp dir),
# no .venv, an empty uv cache (UV_CACHE_DIR in workdir) and no pip cache, so
# every package comes from the registry. "Ready" is the moment the JupyterLab
# started by `rbm-nb demo` serves the explorer notebook. Then the same again in
# the same clone (the second run). Prints both times; leaves workdir behind.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-$(mktemp -d)}
mkdir -p "$work"
git clone -q "$repo" "$work/clone"
export UV_CACHE_DIR="$work/uv-cache" PIP_NO_CACHE_DIR=1 JUPYTER_RUNTIME_DIR="$work/runtime"
unset PYTHONPATH VIRTUAL_ENV NUMBA_CACHE_DIR

ready() {  # start the demo, wait until the explorer is served, stop it
  .venv/bin/rbm-nb demo --no-browser --port 0 > "$work/demo.log" 2>&1 &
  local pid=$! url=""
  for _ in $(seq 1200); do
    url=$(grep -o 'http://[^ ]*' "$work/demo.log" | head -1 || true)
    [ -n "$url" ] && break
    sleep 0.1
  done
  local base=${url%%/lab/*} token=${url##*token=}
  until curl -sf -H "Authorization: token $token" \
      "$base/api/contents/06_head_eye_explorer.ipynb?content=0" > /dev/null; do
    sleep 0.2
  done
  kill "$pid"
  wait "$pid" 2>/dev/null || true
}

cd "$work/clone"
# CPU time next to wall time: on a machine shared with other work the wall
# time mostly measures the others (and the network).
TIMEFORMAT="    setup.sh: %R s wall, %U s user + %S s system CPU"
for run in fresh second; do
  start=$(date +%s.%N)
  time (bash .ci/setup.sh demo 2>&1 | grep -v '^WARNING: Location' | sed 's/^/    /')
  ready
  echo "$run: demo ready after $(echo "$(date +%s.%N) - $start" | bc) s (load: $(cut -d' ' -f1-3 /proc/loadavg))"
done
