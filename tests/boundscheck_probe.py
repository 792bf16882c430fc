"""Public calls at the smallest sizes, run under NUMBA_BOUNDSCHECK=1.

Run as a script by ``tests/project/test_boundscheck.py``: every call either
returns or raises a clear error at the door; an ``IndexError`` means a kernel
read outside an array (numba's boundscheck turns such reads into IndexError;
without it they return whatever lies in memory). Prints one line per such
call, then ``checked <n> calls``.
"""

from __future__ import annotations

import warnings

import numpy as np

import rbm_nb as rbm


def _turning(n):
    a = 0.1 * np.arange(n)
    return np.column_stack([np.cos(a / 2), 0 * a, 0 * a, np.sin(a / 2)])


def calls():
    """(label, callable) for frames and arrays of 1 to 4 samples."""
    out = []
    for n in (1, 2, 3, 4):
        t = np.arange(float(n))
        q = _turning(n)
        x = np.column_stack([t, 0 * t, 0 * t])
        for mode in ("quaternion", "rotation_vector"):
            for thresh in (None, 0.1):
                out.append((
                    f"estimate_angular_velocity n={n} mode={mode} outlier={thresh}",
                    lambda q=q, t=t, m=mode, th=thresh: rbm.estimate_angular_velocity(
                        q, timestamps=t, mode=m, outlier_thresh=th
                    ),
                ))  # fmt: skip
        for thresh in (None, 0.1):
            out.append((
                f"estimate_linear_velocity n={n} outlier={thresh}",
                lambda x=x, t=t, th=thresh: rbm.estimate_linear_velocity(
                    x, timestamps=t, outlier_thresh=th
                ),
            ))  # fmt: skip
        for m in (1, 2, 4):
            t_out = np.linspace(0, n - 1, m)
            out.append((
                f"qinterp n={n} m={m}",
                lambda q=q, t=t, to=t_out: rbm.qinterp(q, t, to),
            ))  # fmt: skip
        out.append((f"qmean n={n}", lambda q=q: rbm.qmean(q)))
        pts = np.random.default_rng(n).normal(size=(n, 3))
        out.append(
            (f"best_fit_transform n={n}", lambda p=pts: rbm.best_fit_transform(p, p))
        )
        out.append((f"iterative_closest_point n={n}",
                    lambda p=pts: rbm.iterative_closest_point(p, p)))  # fmt: skip

        def tree(n=n, t=t, q=q, x=x):
            rbm.clear_registry()
            rbm.register_frame("world")
            rbm.register_frame(
                "f", parent="world", translation=x, rotation=q, timestamps=t
            )
            rbm.register_frame(
                "d", parent="world", translation=x, rotation=q, timestamps=t + 0.5,
                discrete=True,
            )  # fmt: skip

        for name in ("lookup_transform", "lookup_pose", "lookup_twist",
                     "lookup_linear_velocity", "lookup_angular_velocity"):  # fmt: skip
            for other in ("world", "d"):
                out.append((
                    f"{name}('f', {other!r}) n={n}",
                    lambda tree=tree, nm=name, o=other: (tree(), getattr(rbm, nm)("f", o)),
                ))  # fmt: skip
        for m in (1, 2, 5):
            tq = np.linspace(-0.5, n, m)
            for name, width in (("transform_points", 3), ("transform_quaternions", 4),
                                ("transform_angular_velocity", 3),
                                ("transform_linear_velocity", 3)):  # fmt: skip
                arr = _turning(m) if width == 4 else np.zeros((m, 3))
                out.append((
                    f"{name} frame n={n} data m={m}",
                    lambda tree=tree, nm=name, a=arr, ts=tq: (
                        tree(), getattr(rbm, nm)(a, "world", "f", timestamps=ts)
                    ),
                ))  # fmt: skip
    return out


def main() -> int:
    warnings.simplefilter("ignore")
    bad = 0
    checked = 0
    for label, call in calls():
        checked += 1
        try:
            call()
        except IndexError as err:
            bad += 1
            print(f"OUT OF BOUNDS: {label}: {err}")
        except Exception:  # clear errors are fine here; the table checks them
            pass
    print(f"checked {checked} calls")
    return bad


if __name__ == "__main__":
    raise SystemExit(1 if main() else 0)
