"""A compiled kernel called through its address, so that the caller's compile
does not link the callee's code (and have LLVM optimise and emit it once more).

numba links every kernel a kernel calls into the caller's own LLVM module and
optimises the whole again: a generated sweep's ``evaluate`` compiled ``settle``
(the careful walk, the watch, the force stage) and ``flush_forces`` a second
time, 1.4 s of its 5.5 s.  ``first_class`` compiles a kernel for the types of
sample arguments and gives its numba function type and its address; the
caller gets the address as an integer (an int64 array's element:
unboxed at no cost, where numba checks a first-class function argument's whole
signature at every call from Python, 8 us each) and ``function_at(address,
FTYPE)`` makes it a function value again, called like the kernel.  The same
compiled code runs, so the same bits.

In numba's Python mode (``NUMBA_DISABLE_JIT=1``) the caller is handed the
kernels themselves and ``function_at`` returns what it is given.
"""

from __future__ import annotations

from numba import config, types, typeof
from numba.core import cgutils
from numba.extending import intrinsic


def _function_at(typingctx, address, ftype):
    """The function of type ``ftype`` (a FunctionType given as a module global:
    numba types it as its TypeRef) compiled at ``address`` (int64): numba then
    calls it as it calls a kernel directly (its own calling convention, its
    status checked), through the address."""
    fty = ftype.instance_type
    if not isinstance(fty, types.FunctionType) or not isinstance(address, types.Integer):
        return None

    def codegen(context, builder, sig, args):
        fn = cgutils.create_struct_proxy(fty)(context, builder)
        vp = context.get_value_type(types.voidptr)
        fn.c_addr = vp(None)
        fn.py_addr = vp(None)
        fn.jit_addr = builder.inttoptr(args[0], vp)
        return fn._getvalue()
    return fty(address, ftype), codegen


if config.DISABLE_JIT:
    def function_at(address, ftype):
        """(numba's Python mode: ``address`` is the kernel itself.)"""
        return address
else:
    function_at = intrinsic(_function_at)


def _unliteral(typingctx, value):
    """``value``, typed as a value known only at run time.  numba types a constant
    argument (``True``, ``50``) as its literal and compiles the callee, and all it
    calls, once per literal: a kernel called with ``True`` in one place and
    ``False`` in another was compiled twice (the friction integrator's evaluation:
    46.6 s into an empty cache, 34.4 s through this).  ``callee(...,
    unliteral(True))`` compiles it once for both: the same operations on the
    same values, so the same bits."""
    target = types.unliteral(value)

    def codegen(context, builder, sig, args):
        return context.cast(builder, args[0], sig.args[0], sig.return_type)
    return target(value), codegen


if config.DISABLE_JIT:
    def unliteral(value):
        """(numba's Python mode: ``value`` itself.)"""
        return value
else:
    unliteral = intrinsic(_unliteral)


def _pick(typingctx, cond, a, b):
    """``a`` where ``cond``, else ``b``: one LLVM ``select`` of two values of the
    same float type, both already computed.  numba writes ``a if cond else b``
    as branches; in a long lane loop LLVM could not hoist a test that the loop
    never changes (the force lanes' choice of the working point among the
    points), turned the branches into one masked store per point (microcoded
    on AMD's AVX2 cores, 12 of the force lanes' 15) and kept them; a select
    chain is a blend per point instead.  The same value, so the same bits."""
    if not (isinstance(cond, types.Boolean) and isinstance(a, types.Float) and a == b):
        return None

    def codegen(context, builder, sig, args):
        return builder.select(args[0], args[1], args[2])
    return a(cond, a, b), codegen


if config.DISABLE_JIT:
    def pick(cond, a, b):
        """(numba's Python mode: ``a if cond else b``.)"""
        return a if cond else b
else:
    pick = intrinsic(_pick)


def first_class(kernel, args):
    """(numba FunctionType, address) of ``kernel`` compiled (or loaded from
    numba's cache) for the types of the sample arguments ``args``: the address
    of the compiled function itself (numba's calling convention: no C wrapper
    between, which would pass every argument once more)."""
    argtypes = tuple(typeof(a) for a in args)
    kernel.compile(argtypes)
    cres = kernel.overloads[argtypes]
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    return types.FunctionType(cres.signature), address
