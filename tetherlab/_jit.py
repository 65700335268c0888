"""Numba set-up shared by every compiled kernel.

Why this module exists:

* Kernels are cached on disk (``cache=True``) so a second run does not recompile.  Numba's
  cache is keyed on the source file of each function only, so a change in a *callee* defined in
  another file can leave a stale machine-code cache behind.  We therefore point numba at a cache
  directory named after a hash of every tetherlab source file: any edit to the package selects a
  fresh directory, and an untouched package reuses its cache across processes.
* The integrators are generic over the right-hand side.  Passing a numba dispatcher as an argument
  makes the argument *type* depend on the function object, which defeats the disk cache.  Passing a
  ``cfunc`` with the fixed signature :data:`RHS_SIG` gives a stable first-class function type, so
  integrator and right-hand side are both compiled and cached, and the call between them is a plain
  function-pointer call (tens of nanoseconds) inside the compiled step loop.

Import this module before defining any jitted function (every kernel module does so).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba
from numba import types

_PKG = Path(__file__).resolve().parent


def _source_digest() -> str:
    h = hashlib.sha1()
    for path in sorted(_PKG.rglob("*.py")):
        h.update(path.relative_to(_PKG).as_posix().encode())
        h.update(path.read_bytes())
    h.update(numba.__version__.encode())
    return h.hexdigest()[:16]


def _cache_root() -> Path:
    explicit = os.environ.get("TETHERLAB_CACHE_DIR")
    if explicit:
        return Path(explicit)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "tetherlab" / "numba"


CACHE_DIR = _cache_root() / _source_digest()
try:
    CACHE_DIR.mkdir(parents=True, exist_ok=True)
    numba.config.CACHE_DIR = str(CACHE_DIR)
except OSError:  # read-only home: numba falls back to __pycache__ next to the sources
    pass

njit = numba.njit


def njit_hot(*args, **kwargs):
    """``njit`` for the kernels of the right-hand side's hot path (the forest driver and the
    chain's walk, elimination and back substitution), which allocate nothing and only borrow the
    arrays their caller owns.  Two settings differ from plain ``njit``; neither changes a result:

    * no reference counting (NRT).  With it, every ``inline="always"`` call taking an array inside
      a loop (a rod's forces, each quadrature node's effects) got an incref/decref pair that numba
      could not prune across the loop: an out-of-line call per node, with every floating-point
      register spilled around it.  Without NRT an allocation in such a kernel is a compile error,
      so "allocates nothing" is checked, not assumed;
    * IEEE division (``error_model="numpy"``): a zero divisor gives inf or nan, which the kernels'
      finiteness checks report as a failure, instead of a test and a branch before every
      division for a ZeroDivisionError the right-hand side cannot raise anyway (its arguments are
      checked first: a rod's length before its direction, masses at load).

    ``fastmath`` stays off: every operation is the IEEE operation the source writes."""
    kwargs["_nrt"] = False
    kwargs.setdefault("error_model", "numpy")
    return numba.njit(*args, **kwargs)


def cache_is_cold() -> bool:
    """True when no kernel of these sources has been compiled into the cache yet (a first run)."""
    try:
        return not any(CACHE_DIR.rglob("*.nbi"))
    except OSError:
        return True


def announce_compilation() -> None:
    """Say on the "tetherlab" logger that the first run compiles the kernels (about a minute,
    longer on a loaded machine), so a first run is not a minute of silence."""
    if cache_is_cold():
        import logging

        logging.getLogger("tetherlab").info(
            "first run of these sources: compiling the numerical kernels (about a minute, once; "
            "cached in %s)", CACHE_DIR,
        )

#: Right-hand-side ABI shared by all compiled integrators:
#: ``status = rhs(t, y_ptr, dydt_ptr, params_ptr)``; status 0 means success, any other value is a
#: model-specific failure code (the model writes details into its own parameter block).
RHS_SIG = types.int64(
    types.float64,
    types.CPointer(types.float64),
    types.CPointer(types.float64),
    types.CPointer(types.float64),
)


def rhs_cfunc(func):
    """Compile ``func(t, y, dydt, p) -> int`` (pointer arguments) as a cached cfunc with RHS_SIG."""
    return numba.cfunc(RHS_SIG, cache=True, nopython=True)(func)


# ------------------------------------------------------------------------------------------------
# Raw data pointers for the rhs ABI.  ``arr.ctypes`` inside a kernel builds an object that holds a
# reference to the array: an atomic NRT incref before the call and a decref after it, for each of
# the three pointer arguments.  Measured on a trivial rhs, that costs ~40 ns per call -- more than
# a DROMO rhs's whole force model -- so the integrators pass these plain pointers instead.  The
# caller keeps the arrays alive for the duration of the call (they are its own locals/arguments).
# ------------------------------------------------------------------------------------------------
from numba.core import cgutils  # noqa: E402
from numba.extending import intrinsic  # noqa: E402


@intrinsic
def ptr(typingctx, arr):
    """``float64*`` to the first element of a C-contiguous float64 array (no reference counting).
    Any other array type fails to compile, so a strided view can never reach the rhs."""
    if not (isinstance(arr, types.Array) and arr.dtype == types.float64 and arr.layout == "C"):
        return None
    sig = types.CPointer(types.float64)(arr)

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, value=args[0])
        return ary.data

    return sig, codegen


@intrinsic
def row_ptr(typingctx, arr, i):
    """``float64*`` to ``arr[i, 0]`` of a 2-D float64 array (no reference counting)."""
    if not (isinstance(arr, types.Array) and arr.dtype == types.float64 and arr.ndim == 2
            and arr.layout == "C" and isinstance(i, types.Integer)):  # fmt: skip
        return None
    sig = types.CPointer(types.float64)(arr, i)

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, value=args[0])
        idx = context.cast(builder, args[1], signature.args[1], types.intp)
        zero = context.get_constant(types.intp, 0)
        return cgutils.get_item_pointer(context, builder, aryty, ary, [idx, zero], wraparound=False)

    return sig, codegen
