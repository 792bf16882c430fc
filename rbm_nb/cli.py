"""The ``rbm-nb`` command.

``rbm-nb demo --text`` prints a lookup across a small moving frame tree: a
quick check that the frame core works, with no Jupyter involved.
"""

from __future__ import annotations

import argparse
import sys


def _text_demo() -> int:
    import numpy as np

    import rbm_nb as rbm

    rbm.clear_registry()
    rbm.register_frame("world")
    # a body walking 5 m along x in 5 s while turning 90 degrees about z
    ts = np.linspace(0.0, 5.0, 6)
    yaw = np.linspace(0.0, np.pi / 2, 6)
    rbm.register_frame(
        "body",
        parent="world",
        translation=np.column_stack([ts, np.zeros(6), np.zeros(6)]),
        rotation=rbm.from_euler_angles(yaw=yaw),
        timestamps=ts,
    )
    # a camera fixed on the body, 10 cm above it
    rbm.register_frame("camera", parent="body", translation=(0.0, 0.0, 0.1))

    print("Frame tree:")
    rbm.render_tree("world")
    position, orientation, stamps = rbm.lookup_pose(
        "camera", "world", return_timestamps=True
    )
    print("\nPose of 'camera' in 'world':")
    print(" time [s]   position [m]              orientation (w, x, y, z)")
    for t, p, q in zip(stamps, position, orientation):
        print(f" {t:6.2f}   {np.array2string(p, precision=3):24s}  "
              f"{np.array2string(q, precision=3)}")
    point = rbm.transform_points((1.0, 0.0, 0.0), outof="world", into="camera")
    print("\nThe world point (1, 0, 0) seen from 'camera' over time:")
    print(np.array2string(point, precision=3))
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="rbm-nb", description="rbm_nb: rigid body motion in Jupyter."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run the demo")
    demo.add_argument(
        "--text",
        action="store_true",
        help="print a lookup across a small moving frame tree and exit",
    )
    args = parser.parse_args(argv)
    if args.command == "demo":
        return _text_demo()
    parser.error(f"unknown command {args.command!r}")
    return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
