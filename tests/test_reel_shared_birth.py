"""Several reels at their bounds at one instant (docs/deployment.md 17.1): every one of them gets
its birth or retirement when the phase ends there, and the remaps one after the other keep mass,
momentum and angular momentum to the round-off of a remap (docs/deployment.md 6.3, the verify
study's bounds).

The scene: the free-space scene of the verify study (studies/deployment.py free_scene) with a
second line, the mirror image of the first (-x), paid out by the same law, so both first rods
reach a bound at the same instant.
"""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab.deployment import simulate_reel
from tetherlab.scene import Scene

from .helpers import import_study

_STUDY = import_study("deployment")


def _twin_scene(*, speed: str, length: str, duration: str) -> Scene:
    """A 100 kg body paying out (or hauling in) two equal lines along +x and -x, 10 g/m, EA 2 kN,
    rods of 50 m, each to a 10 kg end mass moving sideways at 0.5 m/s in opposite senses (the pair
    spins about the body), the whole drifting at 1 m/s along x."""
    L = float(length.split()[0])
    reel = {"law": "constant", "speed": speed, "rod_length": "50 m", "stored_length": "2 km", "exit": "canister"}
    ends = {"a": (1.0, "0.5 m/s"), "b": (-1.0, "-0.5 m/s")}
    # 1 km off the origin and drifting along x at 1 m/s: the libration diagnostics need a centre
    # of mass with a nonzero r x v
    bodies = {"m0": {"mass": "100 kg", "position": ["0 m", "1000 m", "0 m"], "velocity": ["1 m/s", "0 m/s", "0 m/s"]}}
    tethers = {}
    for name, (sgn, vy) in ends.items():
        bodies[name] = {"mass": "10 kg", "position": [f"{sgn * L} m", "1000 m", "0 m"], "velocity": ["1 m/s", vy, "0 m/s"]}
        tethers[f"t{name}"] = {"from": "m0", "to": name, "length": length, "EA": "2e3 N", "linear_density": "0.01 kg/m",
                               "model": "energy", "reel": dict(reel)}  # fmt: skip
    return Scene.from_dict({
        "name": "twin-deploy", "duration": duration, "effects": {}, "bodies": bodies, "tethers": tethers,
        "integrator": {"method": "dop853", "rtol": _STUDY.FREE_RTOL, "atol": 1e-11}, "output": {"count": 21},
    })  # fmt: skip


def _mass_kg(length_m: float) -> float:
    """The three bodies and both lines, deployed and stored (10 g/m)."""
    return 120.0 + 2 * 0.01 * (length_m + 2000.0)


def _check_remaps(run, length_m: float, l_before: float, l_after: float, t_change: float, rods: int) -> None:
    # both changes at the one instant, in one end of phase (no zero-length phase between them)
    assert [c["t_s"] for c in run.changes] == [pytest.approx(t_change, abs=1e-9)] * 2
    assert sorted(c["reel"] for c in run.changes) == ["ta", "tb"]
    assert len(run.phases) == 2
    last = run.reel.groupby("reel").tail(1)
    assert last["rods"].tolist() == [rods, rods]
    # mass: the deployed length is the same on both sides of the remap, the first rod is cut (or
    # merged) to the bound less (plus) one rod: the rods hold the same line (1e-9 m: the law's
    # length at the change time, computed twice)
    for _, g in run.reel.groupby("reel"):
        j = int(np.flatnonzero(np.diff(g["phase"].to_numpy()))[0])
        before, after = g.iloc[j], g.iloc[j + 1]
        assert after["deployed_length_m"] == pytest.approx(before["deployed_length_m"], abs=1e-9)
        assert before["rod_length_m"] == pytest.approx(l_before, abs=1e-9)
        assert after["rod_length_m"] == pytest.approx(l_after, abs=1e-9)
    jp, jh = _STUDY.remap_bounds(run, _mass_kg(length_m))
    assert _STUDY.remap_jumps(run.invariants, "momentum") <= jp
    assert _STUDY.remap_jumps(run.invariants, "angmom") <= jh
    # nothing trivial: the pair spins (2 x 10 kg x 150 m x 0.5 m/s about z) and the whole drifts
    assert abs(float(run.invariants["angmom_z_kg_m2_s"].iloc[0])) > 1000.0
    assert float(run.invariants["momentum_x_N_s"].iloc[0]) > 100.0


def test_two_reels_at_the_birth_bound_together_are_both_born():
    # 150 m: first rods of 50 m, born at 75 m (1.5 rods): both at t = 25 m / 2 m/s = 12.5 s
    run = simulate_reel(_twin_scene(speed="2 m/s", length="150 m", duration="20 s"))
    assert [c["change"] for c in run.changes] == ["birth", "birth"]
    _check_remaps(run, 150.0, 75.0, 25.0, 12.5, 4)


def test_two_reels_at_the_retirement_bound_together_both_retire():
    # 300 m hauled in: first rods of 50 m, merged at 12.5 m (a quarter rod): both at t = 37.5 / 2 = 18.75 s
    run = simulate_reel(_twin_scene(speed="-2 m/s", length="300 m", duration="24 s"))
    assert [c["change"] for c in run.changes] == ["retire", "retire"]
    _check_remaps(run, 300.0, 12.5, 62.5, 18.75, 5)
