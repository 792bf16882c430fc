"""The route of ``rbm.transform_points(p, "world", "eye")`` through the code.

Traces (``sys.setprofile``) every call into a Python function of rbm_nb, and
every numba kernel called from rbm_nb, during one warm call through a static
chain and one through a moving chain, and prints the call tree: the depth of
a line is the number of hops from the public name to that function. The
first call of each kind is made untraced (numba compiles, caches fill); the
traced call is the one a user makes again and again.

Run: ``PYTHONPATH=. python benchmarks/transform_points_route.py``.
"""

from __future__ import annotations

import sys

import numpy as np

import rbm_nb as rbm


def _register(moving: bool) -> None:
    rbm.clear_registry()
    rbm.register_frame("world")
    if moving:
        t = np.arange(100) * 0.01
        position = np.c_[t, np.zeros_like(t), np.ones_like(t)]
        half = 0.5 * t
        orientation = np.c_[np.cos(half), 0 * t, 0 * t, np.sin(half)]
        rbm.register_frame(
            "head", translation=position, rotation=orientation, timestamps=t,
            parent="world",
        )  # fmt: skip
    else:
        rbm.register_frame(
            "head", translation=(0.0, 0.0, 1.7), rotation=(1.0, 0.0, 0.0, 0.0),
            parent="world",
        )  # fmt: skip
    rbm.register_frame(
        "eye", translation=(0.03, 0.1, 0.0), rotation=(1.0, 0.0, 0.0, 0.0),
        parent="head",
    )  # fmt: skip


def _kernels_patched():
    """Swap every numba kernel rbm_nb can reach for a Python wrapper the
    profiler sees (a compiled dispatcher is called without a profile event);
    returns the undo list. Call only after the kernels have compiled."""
    from numba.core.registry import CPUDispatcher

    undo = []

    def wrap(kernel):
        def kernel_call(*args, **kwargs):
            return kernel(*args, **kwargs)

        kernel_call.kernel = f"{kernel.py_func.__module__}.{kernel.__name__}"
        return kernel_call

    for module in [m for name, m in sys.modules.items() if name.startswith("rbm_nb")]:
        for attr, value in list(vars(module).items()):
            if isinstance(value, CPUDispatcher):
                undo.append((module, attr, value))
                setattr(module, attr, wrap(value))
    return undo


def _route(call) -> list[tuple[int, str]]:
    """(depth, module.function) of every rbm_nb call made by ``call()``."""
    found: list[tuple[int, str]] = []
    depth = [-1]  # the lambda that makes the call is depth -1
    undo = _kernels_patched()

    def name_of(frame) -> str | None:
        if frame.f_code.co_name == "kernel_call":
            return frame.f_back and f"{_kernel_name(frame)} [numba kernel]"
        module = frame.f_globals.get("__name__", "")
        if module.startswith("rbm_nb"):
            return f"{module}.{frame.f_code.co_qualname}"
        return None

    def _kernel_name(frame) -> str:
        return (
            frame.f_locals["kernel"].py_func.__module__
            + "."
            + (frame.f_locals["kernel"].__name__)
        )

    outside = [0]

    def profile(frame, event, arg):
        if event == "call":
            if outside[0]:
                outside[0] += 1
                return
            name = name_of(frame)
            if name is None and depth[0] >= 0:
                outside[0] = 1  # outside rbm_nb: not counted, not descended
                return
            if name is not None:
                found.append((depth[0], name))
            depth[0] += 1
        elif event == "return":
            if outside[0]:
                outside[0] -= 1
                return
            depth[0] -= 1

    sys.setprofile(profile)
    try:
        call()
    finally:
        sys.setprofile(None)
        for module, attr, value in undo:
            setattr(module, attr, value)
    return found


def _module_of(name: str) -> str:
    parts = name.split(" ")[0].split(".")
    while ".".join(parts) not in sys.modules:
        parts.pop()
    return ".".join(parts)


def main() -> None:
    p = np.array([[0.1, 0.2, 0.3]])
    for label, moving in (("static chain", False), ("moving chain", True)):
        _register(moving)
        rbm.transform_points(p, "world", "eye")  # compile and fill the caches
        route = _route(lambda: rbm.transform_points(p, "world", "eye"))
        kernel = [d for d, n in route if n.endswith("[numba kernel]")]
        modules = {_module_of(n) for _, n in route}
        print(
            f"\n{label}: {len(route)} calls in rbm_nb, {len(modules)} modules, "
            f"kernel at depth {kernel[0] if kernel else None}"
        )
        for d, n in route:
            print(f"{'  ' * d}{n}")


if __name__ == "__main__":
    main()
