"""The hanging chain with a tip mass: the released start against the start a user writes first,
and the TMED rods' lateral modes against the continuum and the rigid-link chain
(docs/hanging-chain.md sections 3-4).

    PYTHONPATH=. python studies/hanging_chain.py [--rods 4,8,16,32] [--rtol 1e-8]

For each rod count it runs, 35 s with RADAU5, two starts of the same swing, 1 % off the vertical:
studies/scenes/hanging-chain-placed.toml (the end mass held at the unstretched length 1 % off the
vertical, the static shape, released) and studies/scenes/hanging-chain.toml with
``release = { angle = asin(0.01) }`` (the free hang turned by that angle, every rod at its release
tension), and prints per start: the axial energy injected (the elastic energy of the rods'
length difference from the lengths with no axial acceleration at t = 0, same directions:
tetherlab.initial.release.axial_energy_J), RADAU5 steps, rejections and wall time (the run's own
``total_wall_s``, set-up included, and its integration ``wall_s``), and the first lateral
frequency fitted to the end mass's sideways motion against the Bessel solution.
"""

from __future__ import annotations

import argparse
import math
import pathlib

import numpy as np

import tetherlab
from tetherlab.initial.release import axial_energy_J, consistent_lengths
from tetherlab.oracles.continuum import fit_frequencies
from tetherlab.oracles.hanging_chain import continuum_frequencies
from tetherlab.pipeline import prepare

SCENES = pathlib.Path(__file__).resolve().parent / "scenes"
CASE = dict(length_m=10.0, mass_kg=1.0, tip_mass_kg=0.5, g_m_s2=9.80665)


def run_start(scene, n: int, rtol: float) -> dict:
    s = scene.replace(**{"tethers.main.rods": n, "integrator.rtol": rtol, "integrator.atol": rtol})
    prep = prepare(s)
    y_c, _ = consistent_lengths(prep.model, prep.y0, prep.model.fresh_params())
    energy = axial_energy_J(prep.model, prep.y0, y_c)
    res = tetherlab.simulate(s, progress=False)
    ts = res.timeseries
    w1 = continuum_frequencies(*CASE.values(), count=1)[0]
    w, amp, rms = fit_frequencies(ts["t_s"].to_numpy(), ts["tip.x_m"].to_numpy(), [w1])
    st = res.stats
    return {
        "n": n, "axial_energy_J": energy, "steps": st["n_accepted"], "rejected": st["n_rejected"],
        "rhs": st["n_rhs"], "wall_s": st["total_wall_s"], "integration_s": st["wall_s"],
        "omega_rad_s": float(w[0]), "rel_error": float((w[0] - w1) / w1), "amplitude_m": float(amp[0]), "fit_rms": rms,
    }


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rods", default="4,8,16,32")
    ap.add_argument("--rtol", type=float, default=1e-8)
    args = ap.parse_args(argv)
    release = {"shape": "equilibrium", "release": {"angle": f"{math.asin(0.01)} rad"}}
    starts = {
        "released from the free hang, 1 % off (hanging-chain.toml, release angle)":
            tetherlab.load_scene(SCENES / "hanging-chain.toml").replace(**{"tethers.main.initial": release}),
        "static shape held 1 % off at the unstretched length, let go (hanging-chain-placed.toml)":
            tetherlab.load_scene(SCENES / "hanging-chain-placed.toml"),
    }
    for name, scene in starts.items():
        print(f"## {name} (rtol = atol = {args.rtol:g})")
        print("| n | axial energy injected (J) | steps | rejected | rhs | wall (s) | integration (s) | omega_1 error |")
        print("|---|---|---|---|---|---|---|---|")
        for n in (int(k) for k in args.rods.split(",")):
            r = run_start(scene, n, args.rtol)
            print(f"| {n} | {r['axial_energy_J']:.3g} | {r['steps']} | {r['rejected']} | {r['rhs']} | {r['wall_s']:.3f} "
                  f"| {r['integration_s']:.3f} | {r['rel_error']:.3g} |", flush=True)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
