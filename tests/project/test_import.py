"""``import rbm_nb`` stays light and compiles nothing (timing: benchmarks/)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap


def run(code: str) -> dict:
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True, text=True, timeout=300, check=True,
    )  # fmt: skip
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_import_loads_no_heavy_modules():
    out = run(
        """
        import json, sys
        import rbm_nb
        heavy = ["numba", "xarray", "scipy", "quaternion", "matplotlib", "rbm_nb.core.frames"]
        print(json.dumps({name: name in sys.modules for name in heavy}))
        """
    )
    assert not any(out.values()), out


def test_frame_core_modules_compile_nothing_at_import():
    out = run(
        """
        import json
        import rbm_nb.frames, rbm_nb.lookups, rbm_nb.transforms, rbm_nb._engine.chain
        from rbm_nb._kernels import quaternion, resample
        compiled = {
            f"{mod.__name__}.{name}": len(obj.signatures)
            for mod in (quaternion, resample)
            for name, obj in vars(mod).items()
            if hasattr(obj, "signatures")
        }
        print(json.dumps(compiled))
        """
    )
    assert out and not any(out.values()), out


def test_public_names_resolve_to_the_core():
    out = run(
        """
        import json
        import rbm_nb as rbm
        names = ["ReferenceFrame", "registry", "register_frame", "deregister_frame",
                 "clear_registry", "render_tree", "lookup_transform", "lookup_pose",
                 "lookup_twist", "lookup_linear_velocity", "lookup_angular_velocity",
                 "transform_points", "transform_vectors", "transform_quaternions",
                 "transform_angular_velocity", "transform_linear_velocity"]
        print(json.dumps({n: getattr(rbm, n).__module__ if hasattr(getattr(rbm, n), "__module__") else "" for n in names}))
        """
    )
    assert all(module.startswith("rbm_nb.") for module in out.values()), out
