"""PNG figures of a run directory: what a user looks for first.

* ``libration.png``: each tether's in-plane θ and out-of-plane φ (deg, unwrapped);
* ``tension.png``: the axial force of every rod (N), one colour a tether;
* ``invariants.png``: the change of energy and angular momentum, as errors on a log axis where the
  run's physics conserves them, as plain changes (and said so) where it does not;
* ``shape.png``: the tethers in the orbital frame of the centre of mass, in both planes (radial
  against along-track, radial against cross-track), snapshots spread over one turn of a
  spinning system so that they are not all drawn at the same phase;
* ``altitude.png``, ``elements.png``: altitude, and the osculating a, e, i, Ω, ω of the centre of
  mass, against days for runs of days (every run about a central body);
* ``ground-track.png``: geodetic latitude and longitude (runs about the Earth);
* ``attitude.png`` per rigid body: roll, pitch, yaw, body rates, wheel speeds, control torque;
* a run with reels: ``deployment.png`` and its own ``invariants.png`` (tetherlab/plots_reel.py).

Long runs (more than ``MAX_POINTS`` outputs) are drawn as the band between the minimum and the
maximum of each bin of outputs with the bin mean on it (``ENVELOPE_BINS`` bins), not as thousands of overlapping oscillations. Angles are
unwrapped. :func:`figures` returns the matplotlib figures (the tests read their axes and legends);
:func:`plot_run` saves them.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

#: outputs drawn one by one up to this many; above, the min/max band and the mean of
#: ENVELOPE_BINS bins (few enough that a bin spans several oscillations of a libration, so the
#: mean shows the drift and the band the amplitude, instead of a solid block of lines)
MAX_POINTS = 2000
ENVELOPE_BINS = 400

#: effects whose forces derive from a potential the energy diagnostic includes (the energy is
#: then conserved); angular momentum about the central body's centre is conserved only under a
#: central force (central_gravity, or no effect at all)
ENERGY_CONSERVING = {"central_gravity", "j2", "zonal", "uniform_gravity"}
ANGMOM_CONSERVING = {"central_gravity"}


class PlotError(ValueError):
    """The directory cannot be plotted (not a run directory, or no outputs yet)."""


def _plt():
    import matplotlib

    matplotlib.use("Agg")  # files only; no display on CI machines
    import matplotlib.pyplot as plt

    return plt


def time_axis(t_s: np.ndarray, period_s: float | None = None) -> tuple[np.ndarray, str]:
    """Times in the unit a reader expects for the run's length: days from 2 d on, orbits for a
    run of a few orbits, hours, else seconds."""
    t_s = np.asarray(t_s, float)
    span = float(t_s[-1] - t_s[0]) if t_s.size else 0.0
    if span >= 2 * 86400.0:
        return t_s / 86400.0, "t (days)"
    if period_s is not None and np.isfinite(period_s) and period_s > 0 and span >= 0.5 * period_s:
        return t_s / period_s, "t (orbits)"
    if span >= 2 * 3600.0:
        return t_s / 3600.0, "t (h)"
    return t_s, "t (s)"


def _draw(ax, x, y, label=None, **kw):
    """A line, or for more than MAX_POINTS outputs the min/max band of each bin with its mean."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if x.size <= MAX_POINTS:
        return ax.plot(x, y, label=label, **kw)[0]
    edges = np.linspace(0, x.size, ENVELOPE_BINS + 1).astype(int)
    xs, lo, hi, mean = [], [], [], []
    with np.errstate(invalid="ignore"):
        for a, b in zip(edges[:-1], edges[1:]):
            if b <= a:
                continue
            seg = y[a:b]
            xs.append(x[a:b].mean())
            if np.all(np.isnan(seg)):
                lo.append(np.nan), hi.append(np.nan), mean.append(np.nan)
            else:
                lo.append(np.nanmin(seg)), hi.append(np.nanmax(seg)), mean.append(np.nanmean(seg))
    (line,) = ax.plot(xs, mean, label=label, lw=kw.pop("lw", 0.8), **kw)
    ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.3, lw=0)
    return line


def _unwrap_deg(a_rad) -> np.ndarray:
    a = np.asarray(a_rad, float)
    ok = np.isfinite(a)
    out = np.full_like(a, np.nan)
    if ok.any():
        out[ok] = np.degrees(np.unwrap(a[ok]))
    return out


def _tethers(dg) -> list[str]:
    return [c[: -len(".theta_rad")] for c in dg.columns if c.endswith(".theta_rad")]


def _not_conserved(res) -> tuple[list[str], list[str]]:
    """Why the run's energy and angular momentum are not invariants (empty: they are)."""
    effects = list(res.meta.get("model", {}).get("effects") or [])
    scene = res.scene_dict or {}
    energy = [e for e in effects if e not in ENERGY_CONSERVING]
    angmom = [e for e in effects if e not in ANGMOM_CONSERVING]
    for name, t in (scene.get("tethers") or {}).items():
        if isinstance(t, dict):
            if t.get("damping") not in (None, 0, "0 N s", "0.0 N s"):
                energy.append(f"damping of {name}")
            if t.get("model", "paper") == "paper":
                energy.append(f"the paper model of {name}, whose joints work when rods stretch (docs/model.md)")
    for name, b in (scene.get("bodies") or {}).items():
        if isinstance(b, dict) and (b.get("wheels") or b.get("control")):
            energy.append(f"the wheel motors of {name}")
    return energy, angmom


def figures(run_dir) -> dict:
    """{file name: matplotlib Figure} for a run directory (see the module docstring)."""
    from .result import Result

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise PlotError(f"{str(run_dir)!r} is not a directory: give a directory written by 'tetherlab run'")
    if not (run_dir / "run.json").is_file():
        raise PlotError(f"{str(run_dir)!r} is not a run directory (no run.json in it): give a directory written "
                        f"by 'tetherlab run'")  # fmt: skip
    try:
        res = Result.load(run_dir)
    except (OSError, ValueError) as exc:
        raise PlotError(f"cannot read the run in {str(run_dir)!r}: {exc}") from None
    ts, dg = res.timeseries, res.diagnostics
    if len(dg) == 0 or "t_s" not in dg.columns:
        raise PlotError(f"{str(run_dir)!r} holds no outputs yet (state {res.meta.get('state', '?')!r})")
    plt = _plt()
    period = res.meta.get("model", {}).get("ref_period_s")
    tx, xlabel = time_axis(dg["t_s"].to_numpy(), period)
    figs = {}
    tethers = _tethers(dg)

    if tethers:
        fig, ax = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
        for name in tethers:
            _draw(ax[0], tx, _unwrap_deg(dg[f"{name}.theta_rad"]), label=f"tether {name}")
            _draw(ax[1], tx, _unwrap_deg(dg[f"{name}.phi_rad"]), label=f"tether {name}")
        ax[0].set_ylabel("in-plane θ (deg)")
        ax[1].set_ylabel("out-of-plane φ (deg)")
        ax[1].set_xlabel(xlabel)
        ax[0].legend(loc="upper right", fontsize=8)
        ax[0].set_title("libration angles in the orbital frame (unwrapped)")
        figs["libration.png"] = fig

    force_cols = [c for c in ts.columns if c.endswith(".axial_force_N")]
    if force_cols:
        fig, ax = plt.subplots(figsize=(8, 4))
        names = sorted({c.split(".")[0] for c in force_cols}, key=[c.split(".")[0] for c in force_cols].index)
        colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
        for k, name in enumerate(names):
            cols = [c for c in force_cols if c.startswith(f"{name}.")]
            for j, c in enumerate(cols):
                _draw(ax, tx, ts[c], label=f"tether {name} (rods 1-{len(cols)})" if j == 0 else None,
                      color=colors[k % len(colors)], lw=0.8)  # fmt: skip
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel("axial force EA·ε + D·ε' (N)")
        ax.set_xlabel(xlabel)
        ax.set_title("axial force of every rod (negative: the rod pushes)")
        ax.legend(fontsize=8)
        figs["tension.png"] = fig

    if res.meta.get("reel"):  # a deployment: its material invariants and the reel (plots_reel.py)
        from .plots_reel import reel_figures

        figs.update(reel_figures(plt, run_dir, lambda t: time_axis(t, period)))
    else:
        figs["invariants.png"] = _invariants(plt, res, tx, xlabel)
    if tethers and ts.shape[0] > 0:
        figs["shape.png"] = _shape(plt, res, tethers)
    if "altitude_m" in dg.columns:
        figs.update(_orbit(plt, dg, tx, xlabel))
    for body in [c[: -len(".roll_rad")] for c in dg.columns if c.endswith(".roll_rad")]:
        figs[f"attitude-{body}.png"] = _attitude(plt, ts, dg, body, tx, xlabel)
    src = f"run {run_dir.resolve().name} (scene '{res.scene_dict.get('name', '?')}', saved with tetherlab " \
          f"{res.meta.get('versions', {}).get('tetherlab', '?')})"
    for fig in figs.values():
        fig._tetherlab_source = src  # type: ignore[attr-defined]
    return figs


def _invariants(plt, res, tx, xlabel):
    dg = res.diagnostics
    energy_why, angmom_why = _not_conserved(res)
    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    rows = (
        (ax[0], "energy_error_rel", "ΔE / energy scale", energy_why, "energy"),
        (ax[1], "angmom_error_rel", "|ΔH| / |H₀|", angmom_why, "angular momentum"),
    )
    for a, col, label, why, what in rows:
        y = np.abs(dg[col].to_numpy(float)) if col in dg.columns else np.full(len(tx), np.nan)
        if why:
            # not an invariant of this run: the change itself, on a linear axis, and why
            signed = dg[col].to_numpy(float) if col in dg.columns else y
            _draw(a, tx, signed, color="tab:gray")
            a.set_ylabel(f"{label} (change)")
            text = f"{what}: not conserved by this run's physics ({'; '.join(why)}); the curve is the change, not an error"
            a.set_title(textwrap.fill(text, 110), fontsize=7, loc="left")
            continue
        nonzero = y[np.isfinite(y) & (y > 0)]
        if nonzero.size == 0:
            a.plot(tx, np.zeros(len(tx)), color="tab:blue")
            a.set_ylabel(label)
            a.set_title(f"{what}: conserved exactly (0 at every output)", fontsize=8, loc="left")
            continue
        # zeros (the first output, exact steps) are left out: a log axis cannot show them, and a
        # floor of 1e-300 would stretch it over 290 decades and flatten every real error
        _draw(a, tx, np.where(y > 0, y, np.nan), color="tab:blue")
        a.set_yscale("log")
        lo = max(float(nonzero.min()), 1e-18)
        a.set_ylim(lo / 3.0, max(float(nonzero.max()) * 3.0, lo * 10.0))
        a.set_ylabel(f"{label} (error)")
        a.set_title(f"{what}: conserved by the model; the curve is the numerical error (largest "
                    f"{float(nonzero.max()):.2g})", fontsize=8, loc="left")  # fmt: skip
    ax[1].set_xlabel(xlabel)
    return fig


def _snapshot_rows(ts, dg, tethers, count: int = 6) -> np.ndarray:
    """Rows for the shape snapshots: spread over one turn of the first tether when it turns more
    than half a turn in the run (a spinning system drawn at evenly spaced times commensurate with
    its spin would show the same phase each time), else over the run. The turn is measured by θ
    in the orbital frame, or without an orbit frame (free space) by the angle the tether's
    root-to-tip direction sweeps from output to output."""
    n = len(dg)
    if n <= count:
        return np.arange(n)
    t = dg["t_s"].to_numpy(float)
    th = dg[f"{tethers[0]}.theta_rad"].to_numpy(float) if f"{tethers[0]}.theta_rad" in dg.columns else np.full(n, np.nan)
    if np.all(np.isfinite(th)):
        turned = np.unwrap(th)
        swept = turned[-1] - turned[0]
    else:
        nodes = sorted({int(c.split(".")[1][4:]) for c in ts.columns if c.startswith(f"{tethers[0]}.node") and c.endswith(".x_m")})
        d = np.stack([ts[f"{tethers[0]}.node{nodes[-1]}.{a}_m"].to_numpy(float) - ts[f"{tethers[0]}.node{nodes[0]}.{a}_m"].to_numpy(float)
                      for a in "xyz"], axis=1)  # fmt: skip
        u = d / np.linalg.norm(d, axis=1, keepdims=True)
        swept = float(np.nansum(np.arccos(np.clip(np.einsum("ij,ij->i", u[1:], u[:-1]), -1.0, 1.0))))
    rate = swept / (t[-1] - t[0]) if t[-1] > t[0] else 0.0
    if abs(swept) > np.pi and rate != 0.0:
        turn = 2 * np.pi / abs(rate)
        want = t[0] + turn * np.arange(count) / count
        return np.unique(np.searchsorted(t, want).clip(0, n - 1))
    return np.linspace(0, n - 1, count).astype(int)


def _shape(plt, res, tethers):
    from .diagnostics import orbital_frame

    ts, dg = res.timeseries, res.diagnostics
    fig, ax = plt.subplots(1, 2, figsize=(10, 5))
    roots = [c[: -len(".vx_m_s")] for c in ts.columns if c.endswith(".vx_m_s")]
    rows = _snapshot_rows(ts, dg, tethers)
    period = res.meta.get("model", {}).get("ref_period_s")
    tx, label = time_axis(ts["t_s"].to_numpy(float), period)
    unit = label[3:-1]
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(rows)))
    for name in tethers:
        nodes = sorted({int(c.split(".")[1][4:]) for c in ts.columns if c.startswith(f"{name}.node") and c.endswith(".x_m")})
        for k, row in enumerate(rows):
            P = np.array([[ts[f"{name}.node{j}.{a}_m"].iloc[row] for a in "xyz"] for j in nodes])
            r = np.array([ts[f"{roots[0]}.{a}_m"].iloc[row] for a in "xyz"])
            v = np.array([ts[f"{roots[0]}.v{a}_m_s"].iloc[row] for a in "xyz"])
            F = orbital_frame(r[None], v[None])[0]
            if not np.all(np.isfinite(F)):
                F = np.eye(3)  # no orbit (free space): the scene's own axes
            loc = (P - P[0]) @ F.T
            lab = f"{name}, t = {tx[row]:.3g} {unit}" if len(tethers) > 1 else f"t = {tx[row]:.3g} {unit}"
            ax[0].plot(loc[:, 1], loc[:, 0], "o-", ms=2, color=colors[k], label=lab)
            ax[1].plot(loc[:, 2], loc[:, 0], "o-", ms=2, color=colors[k])
    ax[0].set_xlabel("along-track (m)")
    ax[0].set_ylabel("radial (m)")
    ax[0].set_title("orbit plane", fontsize=9)
    ax[1].set_xlabel("cross-track (m)")
    ax[1].set_ylabel("radial (m)")
    ax[1].set_title("across the orbit plane", fontsize=9)
    for a in ax:
        a.set_aspect("equal", adjustable="datalim")
    ax[0].legend(fontsize=7, title="tether shape, from its root", title_fontsize=7)
    return fig


def _orbit(plt, dg, tx, xlabel) -> dict:
    out = {}
    fig, ax = plt.subplots(figsize=(8, 4))
    _draw(ax, tx, dg["altitude_m"].to_numpy(float) / 1e3, label="centre of mass, above the mean radius")
    if "geodetic_height_m" in dg.columns:
        _draw(ax, tx, dg["geodetic_height_m"].to_numpy(float) / 1e3, label="geodetic height (WGS 84)", lw=0.6)
    ax.set_ylabel("altitude (km)")
    ax.set_xlabel(xlabel)
    ax.legend(fontsize=8)
    ax.set_title("altitude of the centre of mass")
    out["altitude.png"] = fig

    fig, ax = plt.subplots(5, 1, sharex=True, figsize=(8, 9))
    _draw(ax[0], tx, dg["a_m"].to_numpy(float) / 1e3)
    ax[0].set_ylabel("a (km)")
    _draw(ax[1], tx, dg["eccentricity"].to_numpy(float))
    ax[1].set_ylabel("e (-)")
    for a, col, lab in ((ax[2], "inclination_rad", "i (deg)"), (ax[3], "raan_rad", "Ω (deg)"), (ax[4], "argp_rad", "ω (deg)")):
        _draw(a, tx, _unwrap_deg(dg[col]) if col != "inclination_rad" else np.degrees(dg[col].to_numpy(float)))
        a.set_ylabel(lab)
    ax[0].set_title("osculating elements of the centre of mass (angles unwrapped)")
    ax[4].set_xlabel(xlabel)
    out["elements.png"] = fig

    if "latitude_rad" in dg.columns:
        fig, ax = plt.subplots(figsize=(8, 4))
        lon = np.degrees(dg["longitude_rad"].to_numpy(float))
        lat = np.degrees(dg["latitude_rad"].to_numpy(float))
        # a break where the track crosses the antimeridian, not a line across the map
        jump = np.r_[False, np.abs(np.diff(lon)) > 180.0]
        lon = np.where(jump, np.nan, lon)
        ax.plot(lon, lat, lw=0.5, label="centre of mass")
        ax.set_xlim(-180, 180)
        ax.set_ylim(-90, 90)
        ax.set_xlabel("longitude (deg)")
        ax.set_ylabel("geodetic latitude (deg)")
        ax.set_title("ground track (Earth rotation angle from the scene's epoch, 0 without one)", fontsize=9)
        ax.legend(fontsize=8)
        out["ground-track.png"] = fig
    return out


def _attitude(plt, ts, dg, body, tx, xlabel):
    fig, ax = plt.subplots(4, 1, sharex=True, figsize=(8, 9))
    for a in "roll pitch yaw".split():
        _draw(ax[0], tx, _unwrap_deg(dg[f"{body}.{a}_rad"]), label=a)
    ax[0].set_ylabel("attitude (deg)")
    ax[0].set_title(f"rigid body {body}: 3-2-1 angles from its orbit frame (unwrapped), rates, wheels, control",
                    fontsize=9)  # fmt: skip
    ax[0].legend(fontsize=8)
    for a in "xyz":
        col = f"{body}.omega_{a}_rad_s"
        if col in ts.columns:
            _draw(ax[1], tx, np.degrees(ts[col].to_numpy(float)), label=f"ω_{a}")
    ax[1].set_ylabel("inertial rate, body axes (deg/s)")
    ax[1].legend(fontsize=8)
    wheels = [c for c in ts.columns if c.startswith(f"{body}.") and c.endswith(".speed_rad_s")]
    for c in wheels:
        _draw(ax[2], tx, ts[c].to_numpy(float) * 60.0 / (2 * np.pi), label=f"wheel {c.split('.')[1]}")
    ax[2].set_ylabel("wheel speed (rpm)")
    if wheels:
        ax[2].legend(fontsize=8)
    else:
        ax[2].set_title("no wheels", fontsize=8, loc="left")
    for a in "xyz":
        col = f"{body}.control_{a}_N_m"
        if col in dg.columns:
            _draw(ax[3], tx, dg[col].to_numpy(float), label=f"u_{a}")
    ax[3].set_ylabel("control torque, body axes (N m)")
    if ax[3].lines:
        ax[3].legend(fontsize=8)
    ax[3].set_xlabel(xlabel)
    return fig


def plot_run(run_dir, out_dir=None) -> list[Path]:
    """Draw the figures of a run directory into ``out_dir`` (default: the run directory)."""
    figs = figures(run_dir)
    out = Path(out_dir or run_dir)
    out.mkdir(parents=True, exist_ok=True)
    plt = _plt()
    return [_save(fig, out / name, plt, fig._tetherlab_source) for name, fig in figs.items()]


def _save(fig, path: Path, plt, sources: str) -> Path:
    from .provenance import stamp_figure

    stamp_figure(fig, sources)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
