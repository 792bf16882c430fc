"""First run from a fresh clone with empty caches, timed (issue 34).

For each of N fresh clones of a committed branch (``git clone`` into
``ROOT/fr-1``, ``ROOT/fr-2``, ...: beside ``ROOT/shared`` as CI has it), with
no uv cache (a new ``UV_CACHE_DIR``), no pip cache and no numba cache, it
runs the README's sequence and times

1. ``bash .ci/setup.sh demo`` (its last line is checked against "M of M"
   or "N of M" with the background compile);
2. ``.venv/bin/rbm-nb demo --no-browser --port 0``: until its URL is printed,
   and until JupyterLab serves the explorer notebook at that URL (then it is
   stopped); how many kernel signatures were compiled at that moment;
3. ``.venv/bin/jupyter nbconvert --to notebook --execute
   notebooks/06_head_eye_explorer.ipynb`` (a fresh kernel right after the
   URL appeared): its wall time and its first cell's time (from the cell
   timings nbclient records in the executed notebook);
4. the per-signature account every process keeps (``rbm_nb-compiles.log``
   in numba's cache folder): how many signatures were compiled before the
   URL and after it, whether any was compiled twice or by the notebook's own
   kernel. The last clone waits for the background compile's end; earlier
   clones stop it, so that the next clone's timing has the cores.

"first run" = wall clock from (1)'s start to (3)'s end, (2) included: the
issue's sequence, fresh clone -> explorer executed (the notebook may wait for
a kernel the background compiles, which goes on during (2), so (1) + (3)
alone would flatter it; it is printed too, as "setup + notebook"). The machine may be shared: each timing comes with the load
average (``uptime``) at its start; read the figures with it.

The recordings are the real ones (``RBM_NB_DATA_DIR=ROOT/shared/data/rbm-data``
when it exists). Clones this script made (marked by a file) are replaced on
the next run; any other folder in the way stops it.

Run:  python3 benchmarks/first_run.py [--clones 3] [--branch issue-34]
      [--repo .] [--root /work]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

MARK = ".first_run_clone"  # says: this script made the folder
NOTEBOOK = "notebooks/06_head_eye_explorer.ipynb"


def uptime() -> str:
    out = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    return out[out.find("load average") :] if "load average" in out else out


def fresh_clone(repo: str, branch: str, target: Path) -> None:
    if target.exists():
        if not (target / MARK).exists():
            sys.exit(f"{target} exists and was not made by this script: stopping")
        shutil.rmtree(target)
    subprocess.run(
        ["git", "clone", "-q", "--branch", branch, repo, str(target)], check=True
    )
    (target / MARK).touch()
    # never committed: keep `git status` of the clone clean
    with open(target / ".git" / "info" / "exclude", "a") as f:
        f.write(f"\n{MARK}\n")


def environment(work: Path, shared: Path) -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR", "UV_CACHE_DIR")
    }
    env["UV_CACHE_DIR"] = tempfile.mkdtemp(prefix="uv-cache-", dir=work)
    env["PIP_NO_CACHE_DIR"] = "1"
    env["JUPYTER_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="runtime-", dir=work)
    data = shared / "data" / "rbm-data"
    if data.is_dir():
        env["RBM_NB_DATA_DIR"] = str(data)
    return env


def run_setup(clone: Path, env: dict[str, str], log: Path) -> tuple[float, str]:
    start = time.perf_counter()
    with open(log, "w") as out:
        proc = subprocess.Popen(
            ["bash", ".ci/setup.sh", "demo"],
            cwd=clone,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        last = ""
        assert proc.stdout is not None
        for line in proc.stdout:
            if line.startswith("WARNING: Location"):
                continue
            stamp = time.perf_counter() - start
            out.write(f"[{stamp:6.1f}] {line}")
            out.flush()
            print(f"      [{stamp:6.1f}] {line}", end="", flush=True)
            last = line.strip()
        if proc.wait() != 0:
            sys.exit(f"setup.sh failed with exit code {proc.returncode}; see {log}")
    return time.perf_counter() - start, last


def compiled_so_far(clone: Path) -> tuple[int, int] | None:
    """(signatures compiled, declared total) from the warm-up's account, if any."""
    account = clone / "rbm_nb" / "_kernels" / "__pycache__" / "rbm_nb-compiles.log"
    status = clone / ".venv" / ".rbm_nb-warm-status"
    try:
        rows = [line.split() for line in account.read_text().splitlines()]
    except OSError:
        rows = []
    compiled = sum(1 for r in rows if len(r) > 1 and r[1] == "compiled")
    try:
        total = int(status.read_text().split()[1])
    except (OSError, IndexError, ValueError):
        return (compiled, 0) if rows else None
    return compiled, total


def demo_url(clone: Path, env: dict[str, str]) -> tuple[float, float, object]:
    """Seconds until ``rbm-nb demo`` prints its URL and serves the notebook.

    Also what was compiled when the URL appeared.
    """
    start = time.perf_counter()
    proc = subprocess.Popen(
        [".venv/bin/rbm-nb", "demo", "--no-browser", "--port", "0"],
        cwd=clone,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        url = ""
        assert proc.stdout is not None
        for line in proc.stdout:
            found = re.search(r"http://\S+", line)
            if found:
                url = found.group(0)
                break
        printed = time.perf_counter() - start
        at_url = compiled_so_far(clone)
        if not url:
            sys.exit("rbm-nb demo printed no URL")
        base, token = url.split("/lab/")[0], url.split("token=")[1]
        request = urllib.request.Request(
            f"{base}/api/contents/06_head_eye_explorer.ipynb?content=0",
            headers={"Authorization": f"token {token}"},
        )
        while True:
            try:
                with urllib.request.urlopen(request, timeout=5) as response:
                    if response.status == 200:
                        break
            except OSError:
                time.sleep(0.1)
            if time.perf_counter() - start > 300:
                sys.exit("JupyterLab did not serve the notebook within 300 s")
        served = time.perf_counter() - start
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return printed, served, at_url


def execute_notebook(
    clone: Path, env: dict[str, str], out: Path
) -> tuple[float, float]:
    """Wall seconds of nbconvert --execute, and its first code cell's seconds."""
    start = time.perf_counter()
    subprocess.run(
        [
            ".venv/bin/jupyter",
            "nbconvert",
            "--to",
            "notebook",
            "--execute",
            NOTEBOOK,
            "--output-dir",
            str(out),
        ],
        cwd=clone,
        env=env,
        check=True,
        capture_output=True,
    )
    wall = time.perf_counter() - start
    executed = json.loads((out / Path(NOTEBOOK).name).read_text())
    first = next(c for c in executed["cells"] if c["cell_type"] == "code")
    timing = first["metadata"]["execution"]
    from datetime import datetime

    def at(key: str) -> datetime:
        return datetime.fromisoformat(timing[key].replace("Z", "+00:00"))

    return wall, (at("shell.execute_reply") - at("iopub.execute_input")).total_seconds()


def background_pids(clone: Path) -> list[int]:
    try:
        text = (clone / ".venv" / ".rbm_nb-warm-pid").read_text()
        return [int(p) for p in text.split()]
    except (OSError, ValueError):
        return []


def wait_background(clone: Path, timeout: float = 1800) -> float | None:
    """Seconds until the background compile's workers are gone (None: none ran)."""
    pids = background_pids(clone)
    if not pids:
        return None
    start = time.perf_counter()
    while any(_alive(p) for p in pids):
        if time.perf_counter() - start > timeout:
            return float("inf")
        time.sleep(0.5)
    return time.perf_counter() - start


def stop_background(clone: Path) -> None:
    """End the clone's background workers (before the next clone is timed)."""
    for pid in background_pids(clone):
        if _alive(pid):
            os.kill(pid, signal.SIGTERM)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    # a zombie is gone for our purpose
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except OSError:
        return False


def account(clone: Path) -> dict[str, int]:
    """Who compiled what, from rbm_nb-compiles.log: counts per signature."""
    path = clone / "rbm_nb" / "_kernels" / "__pycache__" / "rbm_nb-compiles.log"
    try:
        rows = [line.split() for line in path.read_text().splitlines() if line]
    except OSError:
        return {}
    compiled: dict[str, int] = {}
    by_user = 0
    loaded = 0
    for row in rows:
        if row[1] == "compiled":
            compiled[row[0]] = compiled.get(row[0], 0) + 1
            by_user += row[4] != "warm-up"
        else:
            loaded += 1
    return {
        "signatures compiled": len(compiled),
        "compiled twice": sum(n > 1 for n in compiled.values()),
        "compiled by the notebook itself": by_user,
        "put off, then loaded by a worker": loaded,
    }


def main(argv: list[str] | None = None) -> int:
    here = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--clones", type=int, default=3)
    parser.add_argument("--repo", default=str(here))
    parser.add_argument(
        "--branch",
        default=subprocess.run(
            ["git", "-C", str(here), "rev-parse", "--abbrev-ref", "HEAD"],
            capture_output=True,
            text=True,
        ).stdout.strip(),
    )
    parser.add_argument("--root", default=str(here.parent))
    args = parser.parse_args(argv)
    root = Path(args.root)
    rows = []
    for n in range(1, args.clones + 1):
        clone = root / f"fr-{n}"
        print(f"clone {n}: {args.repo} ({args.branch}) -> {clone}", flush=True)
        fresh_clone(args.repo, args.branch, clone)
        work = Path(tempfile.mkdtemp(prefix=f"first-run-{n}-"))
        env = environment(work, root / "shared")
        print(f"  setup.sh demo    ({uptime()})", flush=True)
        setup, last = run_setup(clone, env, work / "setup.log")
        print(f"  url              ({uptime()})", flush=True)
        printed, served, at_url = demo_url(clone, env)
        print(f"  nbconvert        ({uptime()})", flush=True)
        wall, first_cell = execute_notebook(clone, env, work)
        at_notebook_end = compiled_so_far(clone)
        print(
            f"  first run {setup + served + wall:.1f} s wall (setup {setup:.1f}, "
            f"demo started and stopped {served:.1f}, notebook {wall:.1f}); URL at {setup + printed:.1f} s, served at "
            f"{setup + served:.1f} s; first cell {first_cell:.1f} s; compiled at the "
            f"URL {at_url}, at the notebook's end {at_notebook_end}",
            flush=True,
        )
        if n == args.clones:  # the last clone: how long the rest takes
            print(f"  background       ({uptime()})", flush=True)
            background = wait_background(clone)
        else:  # the next clone's timing must not share the cores with it
            background = None
            stop_background(clone)
        sigs = account(clone)
        row = {
            "setup": setup,
            "url": setup + printed,
            "served": setup + served,
            "notebook": wall,
            # wall clock from the set-up's start to the executed notebook, the
            # demo's start in between included: the notebook may wait for a
            # kernel the background compiles, which went on meanwhile
            "first run": setup + served + wall,
            "setup + notebook": setup + wall,
            "first cell": first_cell,
            "background left": background,
            "compiled at url": at_url,
            "compiled at notebook end": at_notebook_end,
            "account": sigs,
            "last line": last,
        }
        rows.append(row)
        print(f"  clone {n}: {json.dumps(row, default=str)}", flush=True)
    print(f"\n{len(rows)} fresh clone(s) of {args.branch}; load now: {uptime()}")
    for key in (
        "setup",
        "url",
        "served",
        "notebook",
        "first run",
        "setup + notebook",
        "first cell",
    ):
        values = [r[key] for r in rows]
        print(
            f"  {key:>11}: min {min(values):6.1f} s   median "
            f"{statistics.median(values):6.1f} s   max {max(values):6.1f} s"
        )
    for n, r in enumerate(rows, 1):
        done, total = r["compiled at url"] or (None, None)
        end, _ = r["compiled at notebook end"] or (None, None)
        background = (
            f"the rest compiled {r['background left']:.0f} s after the notebook"
            if r["background left"] is not None
            else "the rest stopped for the next clone"
        )
        print(
            f"  clone {n}: signatures compiled before the URL {done} of {total}, "
            f"after it {None if done is None or not total else total - done} "
            f"({None if end is None or done is None else end - done} of them by the "
            f"notebook's end); {background}; {r['account']}"
        )
        print(f"           setup's last line: {r['last line']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
