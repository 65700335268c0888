"""PNG figures of a run: libration angles, axial force per rod, invariant errors, tether shape."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")  # files only; no display on CI machines
    import matplotlib.pyplot as plt

    return plt


def plot_run(run_dir, out_dir=None) -> list[Path]:
    from .diagnostics import orbital_frame
    from .result import Result

    res = Result.load(run_dir)
    out = Path(out_dir or run_dir)
    out.mkdir(parents=True, exist_ok=True)
    plt = _plt()
    ts, dg = res.timeseries, res.diagnostics
    scene_name = res.scene_dict.get("name", "?")
    src = f"run {Path(run_dir).resolve().name} (scene '{scene_name}', saved with tetherlab {res.meta.get('versions', {}).get('tetherlab', '?')})"
    period = res.meta.get("model", {}).get("ref_period_s") or float("nan")
    tx = dg["t_s"] / period if np.isfinite(period) else dg["t_s"]
    xlabel = "t (orbits)" if np.isfinite(period) else "t (s)"
    files = []
    tethers = sorted({c.split(".")[0] for c in dg.columns if c.endswith(".theta_rad")})

    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
    for name in tethers:
        ax[0].plot(tx, np.degrees(dg[f"{name}.theta_rad"]), label=name)
        ax[1].plot(tx, np.degrees(dg[f"{name}.phi_rad"]), label=name)
    ax[0].set_ylabel("in-plane θ (deg)")
    ax[1].set_ylabel("out-of-plane φ (deg)")
    ax[1].set_xlabel(xlabel)
    ax[0].legend(loc="upper right")
    files.append(_save(fig, out / "libration.png", plt, src))

    fig, ax = plt.subplots(figsize=(8, 4))
    for c in [c for c in ts.columns if c.endswith(".axial_force_N")]:
        ax.plot(tx, ts[c], label=c.replace(".axial_force_N", ""), lw=0.8)
    ax.set_ylabel("axial force EA·ε + D·ε' (N)")
    ax.set_xlabel(xlabel)
    if len(ax.lines) <= 12:
        ax.legend(fontsize=7)
    files.append(_save(fig, out / "tension.png", plt, src))

    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
    ax[0].plot(tx, np.abs(dg["energy_error_rel"]) + 1e-300)
    ax[0].set_yscale("log")
    ax[0].set_ylabel("|ΔE| / energy scale")
    ax[1].plot(tx, dg["angmom_error_rel"] + 1e-300)
    ax[1].set_yscale("log")
    ax[1].set_ylabel("|ΔH| / |H0|")
    ax[1].set_xlabel(xlabel)
    files.append(_save(fig, out / "invariants.png", plt, src))

    # tether shape in the orbital frame of the centre of mass, a few snapshots
    fig, ax = plt.subplots(figsize=(6, 6))
    roots = [c[: -len(".vx_m_s")] for c in ts.columns if c.endswith(".vx_m_s")]
    for name in tethers:
        nodes = sorted(
            {int(c.split(".")[1][4:]) for c in ts.columns if c.startswith(f"{name}.node") and c.endswith(".x_m")}
        )
        rows = np.linspace(0, len(ts) - 1, min(6, len(ts))).astype(int)
        for row in rows:
            P = np.array([[ts[f"{name}.node{j}.{a}_m"].iloc[row] for a in "xyz"] for j in nodes])
            r = np.array([ts[f"{roots[0]}.{a}_m"].iloc[row] for a in "xyz"])
            v = np.array([ts[f"{roots[0]}.v{a}_m_s"].iloc[row] for a in "xyz"])
            F = orbital_frame(r[None], v[None])[0]
            loc = (P - P[0]) @ F.T
            ax.plot(loc[:, 1], loc[:, 0], "o-", ms=2, label=f"t={tx.iloc[row]:.2f}")
    ax.set_xlabel("along-track (m)")
    ax.set_ylabel("radial (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7)
    files.append(_save(fig, out / "shape.png", plt, src))
    return files


def _save(fig, path: Path, plt, sources: str) -> Path:
    from .provenance import stamp_figure

    stamp_figure(fig, sources)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
