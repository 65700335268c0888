"""The scenes of docs/model.md 12: rigid bodies with wheels and attitude control, hub and spoke, a chain of
three satellites, and the electrodynamic de-orbit with a rigid satellite.

Writes into OUT_DIR ``rigid_scenes.md`` (a table per scene: status, wall time, first integrals),
``rigid_control.png`` (attitude, body rates, wheel speeds, control torque, libration of the
rigid-wheels-control scene), ``hub_spoke.png``, ``chain3.png`` and ``deorbit_rigid.png`` (altitude
of the rigid and the point-mass satellite, the rigid satellite's attitude in its orbit frame), and
``rigid_scenes.csv``.

    PYTHONPATH=. python studies/rigid_scenes.py OUT_DIR [--quick]

``--quick``: every scene shortened (the de-orbit to 1 day), for a smoke test.  The de-orbit pair
runs 3 days by default (the rigid satellite's attitude oscillation bounds the step: the whole
45-day mission took 1073 s and 6.45e6 RADAU5 steps on the shared 2-core machine, commit 4cd66db);
``--full-deorbit`` runs both to the 200 km stop.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from tetherlab.pipeline import simulate
from tetherlab.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "studies" / "scenes"
DAY_S = 86400.0


def _run(name: str, **changes):
    sc = load_scene(SCENES / f"{name}.toml")
    if changes:
        sc = sc.replace(**changes)
    t0 = time.perf_counter()
    res = simulate(sc, progress=False, raise_on_failure=False)
    return res, time.perf_counter() - t0


def _row(name, res, wall, note=""):
    d = res.diagnostics
    row = {
        "scene": name,
        "status": "ok" if res.ok else res.message,
        "simulated_s": float(res.timeseries["t_s"].iloc[-1]),
        "wall_s": wall,
        "steps": res.stats.get("n_accepted"),
        "angmom_error_internal_max": float(np.nanmax(np.abs(d["angmom_error_internal"]))) if len(d) > 1 else float("nan"),
        "energy_error_rel_max": float(np.nanmax(np.abs(d["energy_error_rel"]))) if len(d) > 1 else float("nan"),
        "note": note,
    }
    q = [c for c in d.columns if c.endswith("quat_norm_error")]
    row["quat_norm_error_max"] = float(np.nanmax(np.abs(d[q].to_numpy()))) if q else float("nan")
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("out_dir")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--full-deorbit", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    from tetherlab.provenance import footer, stamp_figure

    rows = []
    lines = ["# Rigid bodies, wheels, trees", ""]

    # -- rigid satellite, three wheels, PD hold, tether at an offset point -----------------------
    res, wall = _run("rigid-wheels-control", **({"duration": "1200 s"} if args.quick else {}))
    rows.append(_row("rigid-wheels-control", res, wall, "energy changes by the motors' work (not conserved)"))
    ts, d = res.timeseries, res.diagnostics
    t = ts["t_s"].to_numpy()
    fig, ax = plt.subplots(5, 1, figsize=(8, 12), sharex=True)
    for a in ("roll", "pitch", "yaw"):
        ax[0].plot(t, np.degrees(d[f"sat.{a}_rad"]), label=a)
    ax[0].set_ylabel("attitude in orbit frame (deg)")
    for a in "xyz":
        ax[1].plot(t, ts[f"sat.omega_{a}_rad_s"], label=f"omega_{a}")
        ax[3].plot(t, d[f"sat.control_{a}_N_m"], label=f"u_{a}")
    ax[1].set_ylabel("body rates (rad/s)")
    for w in ("wx", "wy", "wz"):
        ax[2].plot(t, ts[f"sat.{w}.speed_rad_s"], label=w)
    ax[2].set_ylabel("wheel speed (rad/s)")
    ax[3].set_ylabel("control torque (N m)")
    ax[4].plot(t, np.degrees(d["main.theta_rad"]), label="in-plane theta")
    ax[4].plot(t, np.degrees(d["main.phi_rad"]), label="out-of-plane phi")
    ax[4].set_ylabel("libration (deg)")
    ax[4].set_xlabel("t (s)")
    for a in ax:
        a.legend(fontsize=7, loc="upper right")
        a.grid(alpha=0.3)
    fig.suptitle("rigid-wheels-control: attitude hold while the tether librates")
    stamp_figure(fig, "studies/rigid_scenes.py; studies/scenes/rigid-wheels-control.toml")
    fig.savefig(out / "rigid_control.png", dpi=110)
    plt.close(fig)

    # -- hub and spoke ---------------------------------------------------------------------------
    res, wall = _run("hub-spoke-spin", **({"duration": "120 s"} if args.quick else {}))
    rows.append(_row("hub-spoke-spin", res, wall, "damped tethers: energy decreases; H conserved"))
    ts, d = res.timeseries, res.diagnostics
    t = ts["t_s"].to_numpy()
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax[0].plot(t, ts["hub.omega_z_rad_s"])
    ax[0].set_ylabel("hub spin (rad/s)")
    for k in range(1, 5):
        ax[1].plot(t, ts[f"s{k}.rod1.strain"], label=f"spoke {k}, rod 1")
    ax[1].set_ylabel("strain")
    ax[1].set_xlabel("t (s)")
    ax[1].legend(fontsize=7)
    stamp_figure(fig, "studies/rigid_scenes.py; studies/scenes/hub-spoke-spin.toml")
    fig.savefig(out / "hub_spoke.png", dpi=110)
    plt.close(fig)

    # -- chain of three ----------------------------------------------------------------------------
    res, wall = _run("chain3", **({"duration": "0.2 orbits"} if args.quick else {}))
    rows.append(_row("chain3", res, wall, "conservative: energy and H conserved"))
    d = res.diagnostics
    fig, ax = plt.subplots(figsize=(8, 4))
    for k in ("t1", "t2"):
        ax.plot(d["t_s"], np.degrees(d[f"{k}.theta_rad"]), label=f"{k} in-plane")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("libration (deg)")
    ax.legend()
    stamp_figure(fig, "studies/rigid_scenes.py; studies/scenes/chain3.toml")
    fig.savefig(out / "chain3.png", dpi=110)
    plt.close(fig)

    # -- de-orbit: rigid satellite with an offset attachment beside the point-mass satellite -------
    quick = {} if args.full_deorbit else {"duration": "1 d" if args.quick else "3 d"}
    deorbit = {}
    for name in ("deorbit-ed", "deorbit-ed-rigid"):
        res, wall = _run(name, **quick)
        deorbit[name] = res
        stop = res.stats.get("stopped_by")
        t_end = float(res.timeseries["t_s"].iloc[-1]) / DAY_S
        rows.append(_row(name, res, wall, f"end {t_end:.3f} d ({stop or 'duration'})"))
    fig, ax = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for name, res in deorbit.items():
        ts = res.timeseries
        r = np.linalg.norm(ts[["satellite.x_m", "satellite.y_m", "satellite.z_m"]].to_numpy(), axis=1)
        ax[0].plot(ts["t_s"] / DAY_S, (r - 6378137.0) / 1e3, label=name)
    ax[0].set_ylabel("satellite altitude (km)")
    ax[0].legend()
    d = deorbit["deorbit-ed-rigid"].diagnostics
    for a in ("roll", "pitch", "yaw"):
        ax[1].plot(d["t_s"] / DAY_S, np.degrees(d[f"satellite.{a}_rad"]), label=a, lw=0.6)
    ax[1].set_ylabel("rigid satellite attitude (deg)")
    ax[1].set_xlabel("t (d)")
    ax[1].legend()
    stamp_figure(fig, "studies/rigid_scenes.py; studies/scenes/deorbit-ed.toml, deorbit-ed-rigid.toml")
    fig.savefig(out / "deorbit_rigid.png", dpi=110)
    plt.close(fig)

    df = pd.DataFrame(rows)
    df.to_csv(out / "rigid_scenes.csv", index=False)
    lines += [
        "Every rigid-body scene, run as shipped" + (" (shortened: --quick)" if args.quick else "") + ".",
        "`angmom_error_internal_max`: largest |H(t) - H(0)| over the system's own angular momentum about",
        "its centre of mass (rigid spins included); `energy_error_rel_max`: relative energy change (not an",
        "error where motors work or tethers are damped); `quat_norm_error_max`: largest |1 - |q||.",
        "",
        "| " + " | ".join(df.columns) + " |",
        "|" + "---|" * len(df.columns),
    ]
    for r in rows:
        lines.append("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in r.values()) + " |")
    lines += ["", "![rigid_control](rigid_control.png)", "", "![hub_spoke](hub_spoke.png)", "",
              "![chain3](chain3.png)", "", "![deorbit_rigid](deorbit_rigid.png)", "", footer()]
    (out / "rigid_scenes.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
