"""The figures of a run with reels (``tetherlab plot DIR`` on a directory of tetherlab/reelstore.py).

* ``deployment.png``: the deployed length and the rod count, the exit speed, and the tension the
  line pulls the exit with, against time, one colour a reel;
* ``invariants.png`` (instead of the one of a fixed-length run, whose energy and angular momentum
  are per phase and leave out the stored tether and the energy taken out at the exit): the change
  since the first output of the material momentum, angular momentum and energy plus exit work of
  bodies, rods and stored tether (DeploymentResult.invariants; docs/deployment.md 5 and 8). With no
  effect they are invariants and the curves are the numerical error (and, for angular momentum
  and energy, what retirements change: docs/deployment.md 6.2); with effects they are changes.
"""

from __future__ import annotations

import numpy as np


def reel_figures(plt, run_dir, tx_of) -> dict:
    """{file name: Figure}; ``tx_of(t_s) -> (x, label)`` the run's time axis (plots.time_axis)."""
    from .reelstore import load

    run = load(run_dir)
    figs = {}
    reel, inv = run.reel, run.invariants
    if len(reel):
        fig, ax = plt.subplots(3, 1, sharex=True, figsize=(8, 7))
        twin = ax[0].twinx()
        for name, part in reel.groupby("reel", sort=False):
            x, label = tx_of(part["t_s"].to_numpy())
            line = ax[0].plot(x, part["deployed_length_m"], label=f"reel {name}: deployed length")[0]
            twin.step(x, part["rods"], where="post", color=line.get_color(), ls=":", label=f"reel {name}: rods")
            ax[1].plot(x, part["exit_speed_m_s"], color=line.get_color())
            ax[2].plot(x, part["exit_tension_N"], color=line.get_color())
        ax[0].set_ylabel("deployed length (m)")
        twin.set_ylabel("rods (dotted)")
        ax[1].set_ylabel("exit speed (m/s)")
        ax[2].set_ylabel("tension at the exit (N)")
        ax[2].set_xlabel(label)
        ax[0].legend(loc="upper left", fontsize=8)
        kinds = [c["change"] for c in run.changes]
        ax[0].set_title(f"deployment: {kinds.count('birth')} births, {kinds.count('retire')} retirements, "
                        f"{len(run.phases)} phases" + (" (the whole tether retrieved)" if "retrieved" in kinds else ""))
        figs["deployment.png"] = fig
    if len(inv):
        x, label = tx_of(inv["t_s"].to_numpy())
        effects = (run.phases[0].scene_dict.get("effects") if run.phases else None) or {}
        kind = "change since the first output" if effects else "numerical error (no effect: conserved)"
        # the exit work is a trapezoid on the outputs: its error is part of the energy row (docs/deployment.md 8)
        energy_kind = kind if effects else kind + "; the exit work is integrated on the outputs (docs/deployment.md 8)"
        P = inv[[f"momentum_{a}_N_s" for a in "xyz"]].to_numpy()
        H = inv[[f"angmom_{a}_kg_m2_s" for a in "xyz"]].to_numpy()
        E = inv["energy_plus_exit_work_J"].to_numpy()
        h0 = float(np.linalg.norm(H[0])) or 1.0
        e0 = float(np.abs(inv["kinetic_J"].to_numpy()).max()) or 1.0
        rows = (
            (np.linalg.norm(P - P[0], axis=1), "|ΔP| (N s)", "linear momentum of bodies, rods and stored tether"),
            (np.linalg.norm(H - H[0], axis=1) / h0, "|ΔH| / |H₀|", "angular momentum, stored tether included"),
            (E - E[0], "Δ(E + W_exit) / max KE", "energy plus the work taken out at the exit"),
        )
        kinds_of_row = (kind, kind, energy_kind)
        fig, ax = plt.subplots(3, 1, sharex=True, figsize=(8, 7))
        for a, (y, ylabel, what), how in zip(ax, rows, kinds_of_row):
            if ylabel.startswith("Δ(E"):
                y = y / e0
            a.plot(x, y, color="tab:blue")
            a.set_ylabel(ylabel)
            a.set_title(f"{what}: {how}", fontsize=8, loc="left")
        ax[2].set_xlabel(label)
        figs["invariants.png"] = fig
    return figs
