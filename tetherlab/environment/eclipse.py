"""Earth's shadow: cylindrical and conical (umbra + penumbra) shadow functions with the Sun from
DE421, a switch for effects, and located entry/exit events.  Derivation: docs/environment.md, sec. 5.

Shadow function nu (the sunlit fraction of the solar disc, 1 = full Sun, 0 = umbra):

* cylindrical: nu = 0 when r . s_hat < 0 and |r - (r . s_hat) s_hat| < R_E, else 1 (a shadow of
  radius R_E parallel to the Sun line; no penumbra);
* conical (Montenbruck & Gill 2000, Satellite Orbits, sec. 3.4.2): with the apparent radii
  a = asin(R_S/|s - r|) of the Sun and b = asin(R_E/|r|) of the Earth and their apparent
  separation c = acos(-r . (s - r)/(|r| |s - r|)):
      c >= a + b: nu = 1;   c <= b - a: nu = 0 (umbra);   c <= a - b: nu = 1 - b^2/a^2 (annular);
      else nu = 1 - A/(pi a^2), A = a^2 acos(x/a) + b^2 acos((c - x)/b) - c y,
           x = (c^2 + a^2 - b^2)/(2c), y = sqrt(a^2 - x^2)  (the overlap of two discs).

The Sun's position s (geocentric, ICRF = GCRS axes) is the DE421 Chebyshev fit of
tetherlab/ephemeris.py over the run.  R_E: the scene's central-body radius (spherical Earth;
the oblate shadow differs by up to 21 km at the poles: a few seconds of event time).
R_S = 695700 km (IAU 2015 Resolution B3 nominal solar radius).

Block (``pack``): ``[model code, R_E, R_S, Sun ephemeris block...]``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import ephemeris
from .._jit import njit

SUN_RADIUS_M = 695700e3  # IAU 2015 Resolution B3, nominal solar radius

ECLIPSE_NONE = 0
ECLIPSE_CYLINDRICAL = 1
ECLIPSE_CONICAL = 2
ECLIPSE_CODES = {"none": ECLIPSE_NONE, "cylindrical": ECLIPSE_CYLINDRICAL, "conical": ECLIPSE_CONICAL}


def pack(model: str, ctx: dict, radius_m: float, effect: str) -> list[float]:
    """Shadow block for ``model``; needs the scene's epoch and duration (DE421 fit of the Sun)."""
    from ..errors import SceneError

    if model == "none":
        return [float(ECLIPSE_NONE)]
    epoch = ctx.get("epoch")
    if epoch is None:
        raise SceneError("epoch", f"an ISO date (TDB) for effects.{effect}.eclipse = {model!r} (the Sun's position)", "nothing")
    duration = ctx.get("duration_s")
    if duration is None or not (duration > 0 and math.isfinite(duration)):
        raise SceneError("duration", f"a finite run length for effects.{effect}.eclipse", repr(duration))
    block, err = sun_block(epoch, duration)
    if "meta" in ctx:
        ctx["meta"].setdefault(effect, {})["eclipse"] = {
            "model": model, "sun": "DE421 (skyfield-data), Chebyshev fit", "fit_error_m": err,
            "sun_radius_m": SUN_RADIUS_M, "earth_radius_m": radius_m,
        }
    return [float(ECLIPSE_CODES[model]), radius_m, SUN_RADIUS_M] + block


def sun_block(epoch: str, duration_s: float):
    from ..errors import SceneError

    try:
        position = ephemeris.de421_position_function("sun", epoch)
    except ValueError as exc:
        raise SceneError("epoch", "an epoch inside DE421 (1899-07-29 to 2053-10-09 TDB)", f"{epoch!r}: {exc}") from None
    try:
        return ephemeris.fit_block(position, duration_s)
    except ValueError as exc:
        raise SceneError("epoch", "a run inside DE421 (1899-07-29 to 2053-10-09 TDB)", f"{epoch!r}: {exc}") from None
    finally:
        position.close()


@njit(cache=True)
def fraction_at(code, re, rs, sx, sy, sz, x, y, z):
    """Sunlit fraction nu in [0, 1] at r for the Sun at s (both geocentric, m)."""
    if code == ECLIPSE_CYLINDRICAL:
        s = math.sqrt(sx * sx + sy * sy + sz * sz)
        ux = sx / s
        uy = sy / s
        uz = sz / s
        d = x * ux + y * uy + z * uz
        if d >= 0.0:
            return 1.0
        px = x - d * ux
        py = y - d * uy
        pz = z - d * uz
        return 0.0 if px * px + py * py + pz * pz < re * re else 1.0
    # conical
    dx = sx - x
    dy = sy - y
    dz = sz - z
    ds = math.sqrt(dx * dx + dy * dy + dz * dz)
    r = math.sqrt(x * x + y * y + z * z)
    a = math.asin(min(1.0, rs / ds))
    b = math.asin(min(1.0, re / r))
    cc = -(x * dx + y * dy + z * dz) / (r * ds)
    c = math.acos(max(-1.0, min(1.0, cc)))
    if c >= a + b:
        return 1.0
    if c <= b - a:
        return 0.0
    if c <= a - b:
        return 1.0 - (b * b) / (a * a)
    xx = (c * c + a * a - b * b) / (2.0 * c)
    yy = math.sqrt(max(0.0, a * a - xx * xx))
    area = a * a * math.acos(max(-1.0, min(1.0, xx / a))) + b * b * math.acos(max(-1.0, min(1.0, (c - xx) / b))) - c * yy
    return 1.0 - area / (math.pi * a * a)


@njit(cache=True)
def sunlit_fraction(p, off, t, x, y, z):
    """nu at inertial r and time t for the block at p[off] (1 when the model is "none")."""
    code = int(p[off])
    if code == ECLIPSE_NONE:
        return 1.0
    sx, sy, sz = ephemeris.position(p, off + 3, t)
    return fraction_at(code, p[off + 1], p[off + 2], sx, sy, sz, x, y, z)


# -- diagnostics (Python, after a run) ------------------------------------------------------------


def shadow_function(model: str, t_s, r_m, epoch: str, radius_m: float) -> np.ndarray:
    """nu at each time t_s (s since the TDB epoch) and geocentric position r_m (n, 3)."""
    t_s = np.asarray(t_s, float)
    block = np.array(pack(model, {"epoch": epoch, "duration_s": float(max(t_s.max(), 1.0))}, radius_m, "eclipse"))
    return np.array([sunlit_fraction(block, 0, float(t), *map(float, r)) for t, r in zip(t_s, np.asarray(r_m, float))])


def _margin(code, re, rs, s, r):
    """A continuous function that changes sign at the shadow boundary (entry into any shadow):
    cylindrical: |r_perp| - R_E on the night side (else +R_E); conical: c - (a + b) (penumbra)."""
    if code == ECLIPSE_CYLINDRICAL:
        u = s / np.linalg.norm(s)
        d = float(r @ u)
        perp = np.linalg.norm(r - d * u)
        return perp - re if d < 0 else re + d
    ds = np.linalg.norm(s - r)
    rn = np.linalg.norm(r)
    a = math.asin(rs / ds)
    b = math.asin(min(1.0, re / rn))
    c = math.acos(max(-1.0, min(1.0, -float(r @ (s - r)) / (rn * ds))))
    return c - (a + b)


def eclipse_events(model: str, t_s, y_rv, epoch: str, radius_m: float, mu_m3_s2: float, tol_s: float = 1e-3):
    """Shadow entry and exit times of a trajectory given at output samples.

    ``y_rv``: (n, 6) position and velocity of the body (m, m/s) at ``t_s``.  A sign change of the
    shadow margin between two samples is located by Brent's method on a two-body (Kepler)
    propagation from the earlier sample (over one output step of a LEO orbit, the neglected
    perturbations move the body by metres, i.e. milliseconds of event time).
    Returns a list of {"t_s", "kind": "entry"|"exit"}.
    """
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    code = ECLIPSE_CODES[model]
    t_s = np.asarray(t_s, float)
    y_rv = np.asarray(y_rv, float)
    blk = np.array(pack(model, {"epoch": epoch, "duration_s": float(max(t_s.max(), 1.0))}, radius_m, "eclipse"))
    re, rs = blk[1], blk[2]

    def sun(t):
        blk[3 + ephemeris.B_TC] = math.nan
        return np.array(ephemeris.position(blk, 3, float(t)))

    g = np.array([_margin(code, re, rs, sun(t), y[:3]) for t, y in zip(t_s, y_rv)])
    events = []

    def twobody(_t, y):
        r = y[:3]
        return np.concatenate([y[3:], -mu_m3_s2 * r / np.linalg.norm(r) ** 3])

    for k in np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]:
        sol = solve_ivp(twobody, (t_s[k], t_s[k + 1]), y_rv[k], method="DOP853", rtol=1e-11, atol=1e-6, dense_output=True)
        f = lambda t: _margin(code, re, rs, sun(t), sol.sol(t)[:3])  # noqa: E731
        te = brentq(f, t_s[k], t_s[k + 1], xtol=tol_s)
        events.append({"t_s": float(te), "kind": "entry" if g[k] > 0 else "exit"})
    return events
