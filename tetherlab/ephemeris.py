"""Piecewise Chebyshev fits of third-body positions over one run, evaluated in the compiled loop.

Why: the right-hand side must never call Python (skyfield) per evaluation.  Before integration the
position of a body relative to the central body is sampled from DE421 (through skyfield, offline:
the file ships inside the ``skyfield_data`` package) at Chebyshev nodes on consecutive segments
covering the run, and each segment's coefficients go into the parameter block; the kernel finds
the segment and sums the series with Clenshaw's recurrence (a few dozen flops per coordinate).

Time: the kernel's t is seconds since the scene epoch, and both are TDB (the scene's epoch is
parsed as TDB, and DE421's argument is TDB), so no time-scale conversion happens in the loop.
Axes: ICRF (DE421's), which is also GCRS's for an Earth-centred run.  Positions are geometric
(no light time, no aberration): the gravitational pull acts at the instantaneous position.

Block layout of one fitted body (:func:`fit_block`):
``[t_start_s, segment_s, n_segments, n_coef, fit_error_m, t_cached, x, y, z, coefficients...]``
with coefficients ordered segment by segment, x then y then z, ``n_coef`` each (degree + 1).
``t_cached, x, y, z`` is a one-entry cache written by the kernel: one right-hand-side call
evaluates the effect at the root, the tips and every rod quadrature node at the same t, so the
series is summed once per call instead of 2 + 4 n_rods times (NaN = empty).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Callable

import numpy as np

from ._jit import njit

# Segment length and degree: with 4-day segments and degree 14 the fit error to DE421 is at the
# level of skyfield's own float64 rounding (0.1 mm for the Moon, 0.3 mm for the Sun, measured by
# tests/test_gravity_effects.py::test_chebyshev_fit_matches_skyfield); DE421 itself stores the
# Moon in 4-day segments of degree 12.
SEGMENT_S = 4 * 86400.0
DEGREE = 14
# Fit error at this many points per segment, between the nodes (where the error is largest).
_CHECK_PER_SEGMENT = 24

HEADER = 9  # floats before the coefficients
B_T0, B_SEG, B_NSEG, B_NCOEF, B_ERR, B_TC, B_X, B_Y, B_Z = range(HEADER)

#: NAIF names of the bodies tetherlab can fit, relative to the Earth.
DE421_BODIES = ("moon", "sun")


def de421_path() -> Path:
    """Path of the DE421 kernel shipped by ``skyfield_data`` (never downloaded).

    ``skyfield_data.get_skyfield_data_path()`` is avoided on purpose: it warns about the age of
    its Earth-orientation file, which tetherlab does not use.
    """
    import skyfield_data

    path = Path(skyfield_data.__file__).resolve().parent / "data" / "de421.bsp"
    if not path.is_file():
        raise FileNotFoundError(f"DE421 kernel not found at {path}; install skyfield-data (constraints.txt)")
    return path


def de421_position_function(body: str, epoch_tdb: str) -> Callable[[np.ndarray], np.ndarray]:
    """f(t_s) -> (3, n) geometric ICRF position (m) of ``body`` relative to the Earth at TDB
    ``epoch_tdb`` + t_s seconds.  The kernel file is read into memory and closed at once."""
    from astropy.time import Time
    from skyfield.api import Loader, load_file

    if body not in DE421_BODIES:
        raise ValueError(f"body must be one of {DE421_BODIES}, got {body!r}")
    epoch = Time(epoch_tdb, scale="tdb")
    path = de421_path()
    ts = Loader(str(path.parent)).timescale(builtin=True)
    eph = load_file(str(path))
    try:
        vec = eph[body] - eph["earth"]
        first = max(s.spk_segment.start_jd for s in eph.segments)
        last = min(s.spk_segment.end_jd for s in eph.segments)
    except Exception:
        eph.close()
        raise
    jd1, jd2 = float(epoch.jd1), float(epoch.jd2)

    def position(t_s: np.ndarray) -> np.ndarray:
        t_s = np.atleast_1d(np.asarray(t_s, float))
        jd = jd1 + jd2 + t_s / 86400.0
        if jd.min() < first or jd.max() > last:
            raise ValueError(
                f"DE421 covers JD {first} to {last} (1899-07-29 to 2053-10-09 TDB); "
                f"the run needs JD {jd.min():.3f} to {jd.max():.3f}"
            )
        return vec.at(ts.tdb_jd(jd1, jd2 + t_s / 86400.0)).position.m

    position.close = eph.close  # type: ignore[attr-defined]
    return position


def fit_block(
    position: Callable[[np.ndarray], np.ndarray],
    duration_s: float,
    segment_s: float = SEGMENT_S,
    degree: int | None = None,
) -> tuple[list[float], float]:
    """Chebyshev coefficients of ``position`` on [0, duration_s] plus one spare segment.

    Returns (block, fit_error_m): the block laid out as in the module docstring and the largest
    distance between fit and ``position`` over ``_CHECK_PER_SEGMENT`` points per segment that are
    not fit nodes.  The spare segment covers an integrator that evaluates slightly past the end.
    """
    if degree is None:  # read at call time (tetherlab.mutants lowers it for a negative control)
        degree = DEGREE
    if not (duration_s > 0 and math.isfinite(duration_s)):
        raise ValueError(f"duration_s must be a finite time > 0 s, got {duration_s!r}")
    nseg = int(math.ceil(duration_s / segment_s)) + 1
    n = degree + 1
    nodes = np.cos(np.pi * (np.arange(n) + 0.5) / n)  # Chebyshev points of the first kind
    check = np.linspace(-1.0, 1.0, _CHECK_PER_SEGMENT)
    starts = segment_s * np.arange(nseg)
    t_nodes = (starts[:, None] + 0.5 * (nodes[None, :] + 1.0) * segment_s).ravel()
    t_check = (starts[:, None] + 0.5 * (check[None, :] + 1.0) * segment_s).ravel()
    pos_nodes = np.asarray(position(t_nodes), float).reshape(3, nseg, n)
    pos_check = np.asarray(position(t_check), float).reshape(3, nseg, _CHECK_PER_SEGMENT)
    # Interpolation at the n Chebyshev nodes (well conditioned there: T is orthogonal up to scale).
    T = np.polynomial.chebyshev.chebvander(nodes, degree)  # (n, n)
    coef = np.linalg.solve(T, np.moveaxis(pos_nodes, 2, 0).reshape(n, -1))
    coef = coef.reshape(n, 3, nseg)  # (coef, xyz, seg)
    fitted = np.einsum("kc,cxs->xsk", np.polynomial.chebyshev.chebvander(check, degree), coef)
    err = float(np.max(np.linalg.norm(fitted - pos_check, axis=0)))
    block = [0.0, float(segment_s), float(nseg), float(n), err, math.nan, 0.0, 0.0, 0.0]
    block += np.transpose(coef, (2, 1, 0)).ravel().tolist()  # seg, xyz, coef
    return block, err


@njit(cache=True)
def position(p, off, t):
    """Fitted position (m) at time t (s) from the block starting at p[off] (Clenshaw's recurrence).

    Times outside the fitted span use the nearest segment (a slight extrapolation: the fit covers
    the run plus one segment, so this happens only for t < 0 by an integrator's rounding).
    """
    if p[off + B_TC] == t:
        return p[off + B_X], p[off + B_Y], p[off + B_Z]
    t0 = p[off + B_T0]
    seg = p[off + B_SEG]
    nseg = int(p[off + B_NSEG])
    n = int(p[off + B_NCOEF])
    k = int(math.floor((t - t0) / seg))
    if k < 0:
        k = 0
    elif k >= nseg:
        k = nseg - 1
    tau = 2.0 * (t - t0 - k * seg) / seg - 1.0
    base = off + HEADER + k * 3 * n
    x = _clenshaw(p, base, n, tau)
    y = _clenshaw(p, base + n, n, tau)
    z = _clenshaw(p, base + 2 * n, n, tau)
    p[off + B_TC] = t
    p[off + B_X] = x
    p[off + B_Y] = y
    p[off + B_Z] = z
    return x, y, z


@njit(cache=True)
def _clenshaw(p, base, n, tau):
    b1 = 0.0
    b2 = 0.0
    tt = 2.0 * tau
    for j in range(n - 1, 0, -1):
        b0 = p[base + j] + tt * b1 - b2
        b2 = b1
        b1 = b0
    return p[base] + tau * b1 - b2
