"""Right-hand-side cost of the environment effects (docs/environment.md), per body and per rod.

Each row: central gravity + one effect at one fidelity level, for n = 1, 4, 16 rods.  The cost of
the effect is the time per rhs call minus that of central gravity alone (same n); a straight-line
fit cost(n) = a + b n splits it into the part paid at the two point masses (a; drag only, the
electrodynamic effects act on rods only) and the part per rod (b, paid at the 2 x quadrature nodes
of each rod); the exponent is the log-log slope of the effect's cost between n = 1 and 16.
Measured as tetherlab.benchmarks.effects does (compiled loop over the Cowell cfunc, t advancing
1 s per call, best of 5).  The machine is shared: small differences are noise.
"""

from __future__ import annotations

import math

import numpy as np

from .effects import EPOCH, _time_rhs_advancing

DURATION_S = 10 * 86400.0
RODS = (1, 4, 16)
ED = {"current": 2.0, "dipole_strength": 8e15, "eclipse": "none"}
DRAG = {"area": {"m0": 1.0, "mf": 1.0}, "cd": {"m0": 2.2, "mf": 2.2}, "tether_cd": 2.2}  # per body (m0 root, mf tip)

#: (label, effect name, parameters)
LEVELS = (
    ("electrodynamic, aligned dipole", "electrodynamic", {**ED, "field": "aligned"}),
    ("electrodynamic, tilted dipole", "electrodynamic", {**ED, "field": "tilted"}),
    ("electrodynamic, IGRF-14 deg 13", "electrodynamic", {**ED, "field": "igrf14"}),
    ("electrodynamic, aligned + eclipse (conical)", "electrodynamic", {**ED, "field": "aligned", "eclipse": "conical"}),
    ("OML current, aligned dipole, Chapman", "oml", {"conductivity": 3.5e7, "cathode": "from", "ionosphere": "chapman",
                                                     "electron_density": 1e12, "peak_altitude": 350e3, "scale_height": 100e3,
                                                     **ED, "field": "aligned"}),
    ("OML current, IGRF-14, Chapman", "oml", {"conductivity": 3.5e7, "cathode": "from", "ionosphere": "chapman",
                                             "electron_density": 1e12, "peak_altitude": 350e3, "scale_height": 100e3,
                                             **ED, "field": "igrf14"}),
    ("drag, exponential", "drag", {**DRAG, "atmosphere": "exponential"}),
    ("drag, NRLMSIS 2.1 table", "drag", {**DRAG, "atmosphere": "nrlmsis21", "f107": 150.0, "f107a": 150.0, "ap": 15.0}),
)


def _cost(effects, n, repeats=5):
    import time

    from ..forces import EFFECTS
    from ..formulations.cowell import cowell_rhs
    from ..system import TetherSpec, build_model, chain_state

    mu = 3.986004418e14
    r = 7.378e6
    w = math.sqrt(mu / r**3)
    u = np.array([1.0, 0.0, 0.0])
    tet = TetherSpec("t", n, 5000.0, 7.9e4, 15.0, 0.0, "paper", 392.2, "mf", diameter_m=1.2e-3)
    model = build_model(root_mass_kg=1063.0, tethers=[tet], effects=[(EFFECTS[k], dict(p)) for k, p in effects],
                        central={"mu_m3_s2": mu, "radius_m": 6378137.0}, epoch=EPOCH, duration_s=DURATION_S)
    y = chain_state(model, np.array([r, 0.0, 0.0]), np.array([0.0, r * w * math.cos(0.6), r * w * math.sin(0.6)]),
                    [np.tile(u, (n, 1))], [1e-5], None)
    dy = np.empty_like(y)
    p = model.fresh_params()
    _time_rhs_advancing(cowell_rhs, y, dy, p, 10)
    ncalls = max(2000, int(2e5 / n))
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        _time_rhs_advancing(cowell_rhs, y, dy, p, ncalls)
        best = min(best, (time.perf_counter() - t0) / ncalls)
    return best * 1e6


def bench_rows() -> list[dict]:
    base = {n: _cost([("central_gravity", {})], n) for n in RODS}
    rows = [{"effect": "(central gravity only)", **{f"us/call n={n}": base[n] for n in RODS},
             "per body (us)": float("nan"), "per rod (us)": float("nan"), "exponent": float("nan")}]
    for label, name, params in LEVELS:
        c = {n: _cost([("central_gravity", {}), (name, params)], n) - base[n] for n in RODS}
        b, a = np.polyfit(np.array(RODS, float), np.array([c[n] for n in RODS]), 1)
        expo = (math.log(c[16]) - math.log(c[1])) / math.log(16.0) if c[1] > 0 and c[16] > 0 else float("nan")
        rows.append({"effect": label, **{f"us/call n={n}": base[n] + c[n] for n in RODS},
                     "per body (us)": a / 2.0, "per rod (us)": b, "exponent": expo})
    return rows


if __name__ == "__main__":
    from ..bench import _print_table

    _print_table("Environment effects: rhs cost per body and per rod", bench_rows())
