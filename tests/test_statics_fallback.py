"""The statics solve's way to its fallback (docs/catenary.md 3.1): the plain Newton stops as soon as
it wanders instead of after its 60 iterations, without changing any equilibrium it finds, and loads
that depend on where the rods are (a tether hanging from a point fixed in orbit) have a fallback
of their own, the shooting repeated under the loads of the shape it finds.

The case is tests/test_hanging_chain.py's: 10 m, 1 kg, EA = 1e7 N, a 0.5 kg end mass.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherlab import statics
from tetherlab.forces import central_gravity, uniform_gravity
from tetherlab.statics import held_model, solve
from tetherlab.system import TetherSpec

L_M, MASS_KG, TIP_KG, G, EA_N = 10.0, 1.0, 0.5, 9.80665, 1e7
MU = 3.986004418e14  # m^3/s^2, Earth (IERS conventions 2010, table 1.1)
R_ORBIT = 6.778137e6  # m: 400 km above the WGS 84 equatorial radius
G_ORBIT = MU / R_ORBIT**2  # the pull at the nail, ~8.68 m/s^2


def _held(n, effects=None, central=None):
    spec = TetherSpec("main", n, L_M, EA_N, MASS_KG, tip_mass_kg=TIP_KG, tip_name="tip")
    return held_model(spec, effects or [(uniform_gravity.SPEC, {"g": G})], central)


def _holds():
    out = {}
    for name, angle in (("vertical", 0.0), ("1%", math.asin(0.01)), ("10deg", math.radians(10)),
                        ("45deg", math.radians(45)), ("80deg", math.radians(80)), ("horizontal", 0.5 * math.pi)):
        out[f"{name}@L"] = np.array([L_M * math.sin(angle), 0.0, -L_M * math.cos(angle)])
    out["horizontal@0.9L"] = np.array([0.9 * L_M, 0.0, 0.0])
    out["horizontal@0.5L"] = np.array([0.5 * L_M, 0.0, 0.0])
    out["1%@0.9995L"] = np.array([0.1, 0.0, -9.99499875])  # 5 mm of slack
    out["0.1%@L"] = np.array([0.001 * L_M, 0.0, -L_M * math.sqrt(1.0 - 1e-6)])
    return out


def _solve_counting(model, tip, root=(0.0, 0.0, 0.0), **kw):
    """(equilibrium or the ValueError, the plain Newton's outcome: its iterations or why it stopped)."""
    seen = {}
    real = statics._plain_newton

    def counted(*a, **k):
        try:
            out = real(*a, **k)
        except statics._NoConvergence as exc:
            seen["why"] = str(exc)
            raise
        seen["iterations"] = out[2]
        return out

    statics._plain_newton = counted
    try:
        try:
            eq = solve(model, np.asarray(root, float), tip, **kw)
        except ValueError as exc:
            eq = exc
    finally:
        statics._plain_newton = real
    return eq, seen


@pytest.mark.parametrize("n", [1, 2, 4, 8, 16, pytest.param(32, marks=pytest.mark.slow)])
def test_early_stop_changes_no_equilibrium_newton_finds(n, monkeypatch):
    # Every hold of the grid, solved with the stall test and without it (STALL_ITERATIONS beyond
    # max_iter: the solve of the earlier versions): where the plain Newton converged the two are
    # identical bit for bit; where it failed both reach the fallback and agree bit for bit too.
    model = _held(n)
    for name, tip in _holds().items():
        eq, seen = _solve_counting(model, tip)
        monkeypatch.setattr(statics, "STALL_ITERATIONS", 10**9)
        old, old_seen = _solve_counting(model, tip)
        monkeypatch.undo()
        if isinstance(old, ValueError):
            assert isinstance(eq, ValueError), (n, name)
            continue
        assert ("iterations" in seen) == ("iterations" in old_seen), (n, name, seen, old_seen)
        assert np.array_equal(eq.y, old.y) and np.array_equal(eq.holding_force_N, old.holding_force_N), (n, name)
        assert eq.method == old.method, (n, name)


def test_wandering_newton_stops_early_and_the_fallback_converges():
    # 32 rods held horizontally at 0.9 L: the plain Newton from the sagging guess wanders (no
    # tension, no transverse stiffness), its residual rising at every step from the third on
    # (measured).  It now stops once it has risen STALL_ITERATIONS times in a row, well before its
    # 60 iterations; the shooting then converges.  Negative control: without the test it runs all 60.
    model = _held(32)
    tip = _holds()["horizontal@0.9L"]
    eq, seen = _solve_counting(model, tip)
    assert eq.method == "shooting"
    assert seen["why"].startswith(f"the residual rose in {statics.STALL_ITERATIONS} Newton iterations in a row")
    stopped_at = int(seen["why"].split("stopped at ")[1].rstrip(")"))
    assert stopped_at <= statics.STALL_ITERATIONS + 5, seen
    real = statics.STALL_ITERATIONS
    statics.STALL_ITERATIONS = 10**9
    try:
        old, old_seen = _solve_counting(model, tip)
    finally:
        statics.STALL_ITERATIONS = real
    assert old_seen["why"] == "no convergence in 60 Newton iterations"
    assert np.array_equal(old.y, eq.y)  # the same fallback from the same failure


def _orbit_held(n):
    central = {"mu_m3_s2": MU, "radius_m": 6.378137e6}
    return _held(n, [(central_gravity.SPEC, {})], central)


def _check(eq, n, tip_m, root_m):
    assert eq.residual_N < 1e-12 * EA_N  # the solver's own tolerance: 1e-5 N
    assert np.linalg.norm(eq.joints_m[-1] - tip_m) < 1e-12 * L_M
    assert np.linalg.norm(eq.joints_m[0] - root_m) == 0.0
    assert np.all(eq.axial_force_N > 0.0), eq.axial_force_N.min()


@pytest.mark.parametrize("n", [16, pytest.param(64, marks=pytest.mark.slow)])
@pytest.mark.parametrize("hold", ["horizontal@0.9L", "horizontal@0.5L", "1%@0.9995L"])
def test_orbital_loads_have_a_fallback(n, hold):
    # A nail fixed 400 km above the Earth, the tether pulled towards the centre (the local
    # vertical is -x here), the end mass held as in the uniform-gravity grid.  The plain Newton
    # fails there as it does under uniform gravity; the shooting under the loads of its own shape
    # converges on the model's equations.
    root = np.array([R_ORBIT, 0.0, 0.0])
    # the hold in the local frame: "down" is -x (towards the centre), "sideways" is +z
    h = _holds()[hold]
    tip = root + np.array([h[2], 0.0, h[0]])
    model = _orbit_held(n)
    eq, seen = _solve_counting(model, tip, root, down=(-1.0, 0.0, 0.0))
    assert "iterations" not in seen, "the plain Newton was expected to fail here"
    assert eq.method == "shooting"
    _check(eq, n, tip, root)
    # The same tether under uniform gravity of the nail's pull: the shapes differ by the tidal
    # change of the load over the tether, of relative size L / r (1.5e-6): joints within
    # 10 L^2 / r (1.5e-4 m), and apart by more than round-off (the field is really used).
    flat = solve(_held(n, [(uniform_gravity.SPEC, {"g": G_ORBIT})]), np.zeros(3), h)
    flat_joints = root + flat.joints_m[:, [2, 1, 0]]
    gap = float(np.max(np.abs(eq.joints_m - flat_joints)))
    assert 1e-9 < gap < 10.0 * L_M**2 / R_ORBIT, gap


def test_orbital_fallback_negative_control():
    # Without the shooting under its own loads the same solve fails, naming why.
    root = np.array([R_ORBIT, 0.0, 0.0])
    h = _holds()["horizontal@0.9L"]
    real = statics._field_shot
    statics._field_shot = lambda *a, **k: None
    try:
        with pytest.raises(ValueError, match="no equilibrium with every rod in tension was found"):
            solve(_orbit_held(16), root, root + np.array([h[2], 0.0, h[0]]), down=(-1.0, 0.0, 0.0))
    finally:
        statics._field_shot = real
