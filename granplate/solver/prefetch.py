"""A hint to the processor: bring a row of an array into the cache ahead of its use.

The pair loop in space reads its pairs in order (their indices, coefficients and
histories stream from memory and the processor fetches them ahead by itself), but each
pair's second granule is an index read from the list, whose row the processor cannot
guess. In a packing of a million granules those rows lie in memory, not in the cache,
and the loop waits for each. `prefetch_row` asks for the row of a pair some places ahead
(LLVM's `llvm.prefetch`, one instruction, which never faults and changes no number), so
that it has arrived when its pair's turn comes (docs/benchmarks.md, "A million spheres").
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

#: how many pairs ahead the pair loop asks for a granule's rows: about a memory access's
#: time (~100 ns) over a pair's (~10 ns), with a margin
PAIRS_AHEAD = 32


@intrinsic
def prefetch_row(typingctx, arr, row):
    """Compiled use only: ask for the cache line holding arr[row, 0] (arr a 2D C-ordered
    array, row a valid integer index), to be written soon and kept in every cache level.
    Returns nothing; reads and writes nothing."""
    if not (isinstance(arr, types.Array) and arr.ndim == 2 and isinstance(row, types.Integer)):
        return None

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        r = context.cast(builder, args[1], signature.args[1], types.intp)
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [r, context.get_constant(types.intp, 0)])
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32])
        fn = builder.module.declare_intrinsic("llvm.prefetch", [i8p], fnty)
        # (address, 1: for a write, 3: keep in every cache level, 1: data, not instructions)
        builder.call(fn, [builder.bitcast(ptr, i8p), i32(1), i32(3), i32(1)])
        return context.get_dummy_value()

    return types.void(arr, row), codegen
