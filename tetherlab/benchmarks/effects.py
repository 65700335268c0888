"""Right-hand-side cost per call against the number of effects a scene names (unnamed: never evaluated).

Rows for n = 1 and 16 rods and the effect sets: none; central gravity; + j2; + zonal (J2-J4,
instead of j2); + the DE421 Moon; + the DE421 Sun.  The cost of an effect is the difference
between consecutive rows: it is paid at the root body, at the tip and at the 2 x quadrature
nodes of every rod, so it grows with n.  Measured by a compiled loop calling the Cowell cfunc
(as ``tetherlab.bench.rhs_cost_table`` does) with t advancing 1 s per call, as in an
integration: the DE421 effects cache the body's position for one t only, so a fixed t would
hide the Chebyshev evaluation.  Best of 5 repeats (the machine is shared: take small
differences with care).
"""

from __future__ import annotations

import time

import numpy as np

from .._jit import njit, ptr

#: cumulative effect sets, each a row of the table
EFFECT_SETS = (
    (),
    ("central_gravity",),
    ("central_gravity", "j2"),
    ("central_gravity", "zonal"),
    ("central_gravity", "zonal", "moon_de421"),
    ("central_gravity", "zonal", "moon_de421", "sun_de421"),
)
EPOCH = "2026-01-01T00:00:00"  # TDB; any date in DE421's span
DURATION_S = 10 * 86400.0  # the ephemeris fit covers this (3 segments + 1 spare)


@njit(cache=True)
def _time_rhs_advancing(rhs, y, dy, p, ncalls):
    s = 0
    for k in range(ncalls):
        s += rhs(1.0 * k, ptr(y), ptr(dy), ptr(p))  # as the integrators call it (no refcounting)
    return s


def _defaults(spec) -> dict:
    return {k: float(p.default) for k, p in spec.params.items() if p.default is not None}


def rhs_cost_rows(rods=(1, 16), effect_sets=EFFECT_SETS, repeats: int = 5) -> list[dict]:
    """One row per (rods, effect set): ``{"rods", "n_effects", "effects", "us_per_call"}``."""
    from ..forces import EFFECTS
    from ..formulations.cowell import cowell_rhs
    from ..system import TetherSpec, build_model, chain_state

    mu = 3.986004418e14
    r = 7.4e6
    w = np.sqrt(mu / r**3)
    u = np.array([np.cos(np.pi / 6), 0.0, np.sin(np.pi / 6)])  # out of the equator: J3 is not zero
    rows = []
    for n in rods:
        tet = TetherSpec("t", n, 5000.0, 5e4, 10.0, 0.0, "paper", 100.0, "mf")
        for names in effect_sets:
            model = build_model(
                root_mass_kg=1000.0, tethers=[tet],
                effects=[(EFFECTS[k], _defaults(EFFECTS[k])) for k in names],
                central={"mu_m3_s2": mu, "radius_m": 6378137.0},
                epoch=EPOCH, duration_s=DURATION_S,
            )
            y = chain_state(model, np.array([r, 0.0, 0.0]), np.array([0.0, r * w, 0.0]),
                            [np.tile(u, (n, 1))], [1e-5], np.array([0.0, 0.0, w]))
            dy = np.empty_like(y)
            p = model.fresh_params()
            _time_rhs_advancing(cowell_rhs, y, dy, p, 10)  # compile / warm up
            ncalls = max(2000, int(4e5 / n))  # < DURATION_S: within the fit
            best = np.inf
            for _ in range(repeats):
                t0 = time.perf_counter()
                _time_rhs_advancing(cowell_rhs, y, dy, p, ncalls)
                best = min(best, (time.perf_counter() - t0) / ncalls)
            rows.append({
                "rods": n,
                "n_effects": len(names),
                "effects": " + ".join(names) if names else "(none)",
                "us_per_call": best * 1e6,
            })
    return rows


def main() -> int:
    from ..bench import _print_table

    _print_table("Right-hand-side cost per call against the effects named", rhs_cost_rows())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
