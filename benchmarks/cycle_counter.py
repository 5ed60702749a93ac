"""A cycle counter readable inside numba-compiled code, to see where a kernel spends its time.

``perf`` cannot name the parts of a numba kernel (the compiled code has no symbols it can read), and
numba has no line profiler. :func:`cycles` is LLVM's ``llvm.readcyclecounter`` (the time stamp
counter, ``rdtsc``, on x86-64; 0 on a CPU without one) as a numba intrinsic: a few cycles a
reading, so sections of a few hundred cycles can be told apart.

How the ninth round of ``benchmarks/THROUGHPUT.md`` used it, on an instrumented copy of a kernel
(the product's kernels stay as they are):

1. copy the module, with its relative imports made absolute
   (``sed 's/from \\.\\([a-z_]*\\) import/from paraspace.kinematics.\\1 import/'``);
2. add an ``int64`` array argument ``cyc`` of shape ``(runs, sections)`` to the kernel, one row per
   iteration of its ``prange`` loop (so the threads never write the same row);
3. around each section: ``t0 = cycles()`` ... ``cyc[row, s] += cycles() - t0`` (and counts in
   other columns);
4. replay the kernel's recorded launches (a wrapper that copies its arguments, installed on the
   module attribute the caller reads) with the copy, and sum ``cyc`` over the rows.

The cycles are the counter's ticks (a fixed rate on current x86 CPUs, not the core's clock), summed
over the threads: compare sections with each other, and time whole runs with ``time.perf_counter``.
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

__all__ = ["cycles"]


@intrinsic
def cycles(typingctx):
    """The CPU's cycle counter (``llvm.readcyclecounter``) as an ``int64``, inside numba-compiled
    code only."""
    sig = types.int64()

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.IntType(64), [])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.readcyclecounter")
        return builder.call(fn, [])

    return sig, codegen
