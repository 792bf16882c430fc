"""Prefetch hints for the kernels: ask for a cache line before it is needed.

A fused lookup reads about ten arrays at once (the target times, each
moving frame's times, translations, rotations and squad table rows, and
the results it writes). When another computation has just evicted them
from the caches, the processor's own prefetchers leave much of the wait
for memory exposed: measured on the 2-core VM (AMD EPYC), a lookup of the
head/eye chain on one thread after 64 MB were streamed through the caches
took 3.1-3.3 ms without hints and 2.7 ms with them; with the data in cache,
2.8 and 2.4-2.5 ms.

A hint changes no result: it never faults (an address past the end of an
array is harmless) and is dropped when the memory system is busy.

Both are numba intrinsics, usable only inside compiled code::

    prefetch(a, k)            # element k of a, counted in C order
    prefetch_for_write(a, k)  # the same, for a line that is to be written
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["prefetch", "prefetch_for_write"]

_I8P = ir.IntType(8).as_pointer()
_I32 = ir.IntType(32)
# llvm.prefetch(address, rw, locality, cache type): locality 3 keeps the
# line in every level of the cache; cache type 1 is the data cache
_PREFETCH = ir.FunctionType(ir.VoidType(), [_I8P, _I32, _I32, _I32])


def _typed(array, k, write: int):
    """The signature and code of a hint for element ``k`` of ``array``."""
    if not isinstance(array, types.Array) or not isinstance(k, types.Integer):
        return None
    sig = types.void(array, types.intp)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        address = builder.bitcast(builder.gep(data, [args[1]]), _I8P)
        fn = cgutils.get_or_insert_function(
            builder.module, _PREFETCH, "llvm.prefetch.p0i8"
        )
        flags = [ir.Constant(_I32, write), ir.Constant(_I32, 3), ir.Constant(_I32, 1)]
        builder.call(fn, [address, *flags])
        return context.get_dummy_value()

    return sig, codegen


def _read(typingctx, array, k):
    return _typed(array, k, 0)


def _write(typingctx, array, k):
    return _typed(array, k, 1)


# (typed for the kernels' callers: numba's intrinsic object takes the typing
# context first, which compiled code supplies)
#: Hint that element ``k`` of ``array`` (C order) is to be read soon.
prefetch = cast(Callable[[Any, int], None], intrinsic(_read))
#: Hint that element ``k`` of ``array`` (C order) is to be written soon.
prefetch_for_write = cast(Callable[[Any, int], None], intrinsic(_write))
