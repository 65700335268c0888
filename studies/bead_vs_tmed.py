"""Bead (lumped-mass) model against TMED as the bead and rod counts grow (docs/bead.md).

Three quantities, each for n = 1, 2, 4, 8, 16, 32 interior beads and n TMED rods:

  A. libration: in-plane frequency at theta0 = 0.05 rad (scene libration-inplane.toml), against
     the rigid tether's sqrt(3) omega with its elliptic-integral amplitude correction;
  B. tension at the attachments (m0 and mf) of a tether on the local vertical in relative
     equilibrium (scene vertical-equilibrium.toml), against the exact continuous extensible
     tether in 1/r^2 gravity and the closed-form Hill tension;
  C. the first two out-of-plane lateral-mode frequencies of that taut tether (perturbed along the
     continuous mode shape), against the continuous string with tension varying along it (Hill
     frame) and the uniform-tension string k/(2L) sqrt(T/rho).

Writes OUTDIR/bead_vs_tmed.csv, OUTDIR/bead_vs_tmed.png and OUTDIR/bead_vs_tmed.md.
Derivations and discussion: docs/bead.md.  Run (about 5 min on this machine):

    PYTHONPATH=. python studies/bead_vs_tmed.py reports/bead

The runs of A and C start "corotating" at the exact mean static strain with an axial damping
D = 1e5 N s in both models: damping in T = EA eps + D eps' does not act on the rigid libration
nor, to first order in the amplitude, on lateral motion, and it removes the axial transient of
the start (docs/bead.md, section 6).  TMED's own "equilibrium" start is not used there because
tetherlab.pipeline rejects its Newton solution for n >= 8 (residual 1.4e-9 .. 1e-8 > 1e-9).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import tetherlab  # noqa: E402
from tetherlab.errors import SceneError  # noqa: E402
from tetherlab.oracles import bead as B  # noqa: E402
from tetherlab.oracles import bead_scene as BS  # noqa: E402
from tetherlab.oracles import continuum as C  # noqa: E402
from tetherlab.scene import load_scene  # noqa: E402

SCENES = ROOT / "studies" / "scenes"
COUNTS = (1, 2, 4, 8, 16, 32)
THETA0_RAD = 0.05  # small in-plane amplitude (as tests/test_libration.py)
DAMPING = "1e5 N s"  # axial damping of the A and C runs (see the module docstring)
SETTLE_S = 600.0  # the axial transient is gone (e^-60) after this; fits start there
LATERAL_AMPLITUDE_M = 1.0  # of a 5 km tether: linear regime (stretch ~ (pi A/L)^2 ~ 4e-7)
TETHER = "main"


def _physics(scene):
    """Physical inputs of the scene's tether (SI) and the centre of mass's orbit rate."""
    t = scene.tether(TETHER)
    r_c = float(np.linalg.norm(scene.reference_state()[0]))
    mu = scene.central_body.mu_m3_s2
    return dict(m0=scene.body(t.from_body).mass_kg, mf=scene.body(t.to_body).mass_kg, mt=t.mass_kg,
                L=t.length_m, EA=t.EA_N, mu=mu, r_c=r_c, omega=math.sqrt(mu / r_c**3))  # fmt: skip


def static_elongation(scene) -> float:
    ph = _physics(scene)
    return float(C.exact_vertical_tension(ph["m0"], ph["mf"], ph["mt"], ph["L"], ph["EA"], ph["mu"], ph["r_c"]).elongation)


# ---------------------------------------------------------------------------------------------
# A. libration
# ---------------------------------------------------------------------------------------------
def libration_scene(orbits: float = 3.0):
    base = load_scene(SCENES / "libration-inplane.toml")
    return base.replace(**{
        "tethers.main.initial.theta": f"{THETA0_RAD} rad",
        "tethers.main.initial.strain": static_elongation(base),
        "tethers.main.damping": DAMPING,
        "orbit.motion": "corotating",
        "integrator.method": "radau5",
        "duration": f"{orbits} orbits",
        "output.count": int(1000 * orbits) + 1,
    })  # fmt: skip


def _lib_frequency(t, theta, guess):
    keep = t >= SETTLE_S
    w, _, _ = C.fit_frequencies(t[keep], theta[keep], [guess])
    return float(w[0])


def libration_tmed(n: int, orbits: float = 3.0) -> float:
    scene = libration_scene(orbits).replace(**{"tethers.main.rods": n})
    res = tetherlab.simulate(scene, progress=False)
    d = res.diagnostics
    om = _physics(scene)["omega"]
    return _lib_frequency(d["t_s"].to_numpy(), d["main.theta_rad"].to_numpy(), math.sqrt(3) * om) / om


def libration_bead(n: int, orbits: float = 3.0) -> float:
    scene = libration_scene(orbits)
    bs = BS.bead_from_scene(scene, n)
    res = B.integrate(bs.model, bs.y0, bs.t_out_s, method="radau5")
    th, _ = B.libration_angles(bs.model, res.y, bs.side)
    om = _physics(scene)["omega"]
    return _lib_frequency(res.t, th, math.sqrt(3) * om) / om


def libration_reference(orbits: float = 3.0) -> float:
    om = _physics(libration_scene(orbits))["omega"]
    return C.dumbbell_inplane_frequency(om, THETA0_RAD) / om


# ---------------------------------------------------------------------------------------------
# B. tension at the attachments
# ---------------------------------------------------------------------------------------------
def tension_scene():
    return load_scene(SCENES / "vertical-equilibrium.toml")


def tension_tmed(n: int) -> tuple[float, float]:
    """TMED joint reactions at A_1 (root) and B_n (tip) in the relative equilibrium (NaN when
    tetherlab's equilibrium solve refuses the configuration)."""
    scene = tension_scene().replace(**{"tethers.main.rods": n, "duration": "10 s", "output.count": 2})
    try:
        res = tetherlab.simulate(scene, progress=False)
    except SceneError:
        return math.nan, math.nan
    ts = res.timeseries
    return float(ts["main.joint0.reaction_N"].iloc[0]), float(ts[f"main.joint{n}.reaction_N"].iloc[0])


def tension_bead(n: int) -> tuple[float, float]:
    bs = BS.bead_from_scene(tension_scene(), n)
    f0, ff = B.attachment_forces(bs.model, bs.y0[None])
    return float(f0[0]), float(ff[0])


def tension_references() -> dict:
    ph = _physics(tension_scene())
    ex = C.exact_vertical_tension(ph["m0"], ph["mf"], ph["mt"], ph["L"], ph["EA"], ph["mu"], ph["r_c"])
    hill = C.hill_vertical_tension(ph["m0"], ph["mf"], ph["mt"], ph["L"], ph["omega"])
    return {"exact": (ex.tension_root_N, ex.tension_tip_N), "hill": hill}


# ---------------------------------------------------------------------------------------------
# C. lateral modes
# ---------------------------------------------------------------------------------------------
def lateral_modes(count: int = 3):
    ph = _physics(tension_scene())
    return C.out_of_plane_modes(ph["m0"], ph["mf"], ph["mt"], ph["L"], ph["omega"], count)


def lateral_scene(mode: int, periods: float = 12.0):
    """The vertical scene, corotating at the static strain with axial damping, long enough for
    ``periods`` periods of lateral mode ``mode`` after SETTLE_S, sampled 24 times per period of
    the next mode."""
    modes = lateral_modes(mode + 1)
    base = tension_scene()
    dur = SETTLE_S + periods * 2 * math.pi / modes[mode - 1].omega_rad_s
    dt = 2 * math.pi / modes[mode].omega_rad_s / 24
    return base.replace(**{
        "tethers.main.initial.strain": static_elongation(base),
        "tethers.main.damping": DAMPING,
        "orbit.motion": "corotating",
        "integrator.method": "radau5",
        "duration": f"{dur} s",
        "output.count": int(dur / dt) + 1,
    }), modes  # fmt: skip


def _modal_frequency(t, s_nodes, z_nodes, weights, modes, mode, omega, n_lateral):
    """Frequency of lateral mode ``mode`` from node displacements z (rows, nodes) along the orbit
    normal: project on the continuous mode shape (mass-weighted), then fit sinusoids at the
    translation (omega), rigid (2 omega), target and neighbouring lateral modes."""
    shape = np.array([modes[mode - 1].shape(s) for s in s_nodes])
    q = (z_nodes * (weights * shape)[None, :]).sum(axis=1)
    keep = t >= SETTLE_S
    t, q = t[keep], q[keep]
    target = C.spectral_peak(t, q, 0.75 * modes[mode - 1].omega_rad_s, 1.25 * modes[mode - 1].omega_rad_s)
    guesses = [omega, 2 * omega, target]
    for k in (mode - 1, mode + 1):
        if 1 <= k <= min(n_lateral, len(modes)):
            guesses.append(C.spectral_peak(t, q, 0.75 * modes[k - 1].omega_rad_s, 1.25 * modes[k - 1].omega_rad_s))
    w, _, _ = C.fit_frequencies(t, q, guesses)
    return float(w[2])


def lateral_tmed(n: int, mode: int) -> float:
    """TMED lateral frequency / omega; NaN when n rods have fewer than ``mode`` lateral modes."""
    if n - 1 < mode:  # n rods: n - 1 lateral modes besides the rigid libration
        return math.nan
    scene, modes = lateral_scene(mode)
    ph = _physics(scene)
    s = np.linspace(0.0, ph["L"], n + 1)
    z = LATERAL_AMPLITUDE_M * np.array([modes[mode - 1].shape(x) for x in s])
    phi = np.arcsin(np.diff(z) / np.diff(s))
    scene = scene.replace(**{"tethers.main.rods": n, "tethers.main.initial.shape": "rods",
                             "tethers.main.initial.theta": ["0 rad"] * n,
                             "tethers.main.initial.phi": [f"{float(a)!r} rad" for a in phi]})  # fmt: skip
    res = tetherlab.simulate(scene, progress=False)
    ts = res.timeseries
    zhat = _normal(scene)
    pos = np.stack([ts[[f"main.node{j}.{a}_m" for a in "xyz"]].to_numpy() for j in range(n + 1)], axis=1)
    z_nodes = pos @ zhat
    w = np.full(n + 1, ph["mt"] / n)
    w[1:-1] = ph["mt"] / n
    w[0] = ph["m0"] + 0.5 * ph["mt"] / n
    w[-1] = ph["mf"] + 0.5 * ph["mt"] / n
    z_nodes = z_nodes - (z_nodes @ w)[:, None] / w.sum()
    return _modal_frequency(ts["t_s"].to_numpy(), s, z_nodes, w, modes, mode, ph["omega"], n - 1) / ph["omega"]


def lateral_bead(n: int, mode: int) -> float:
    if n < mode:  # n beads: n lateral modes
        return math.nan
    scene, modes = lateral_scene(mode)
    ph = _physics(scene)
    bs = BS.bead_from_scene(scene, n)
    s = bs.model.node_arclength_m()
    bs = BS.with_lateral_displacement(bs, LATERAL_AMPLITUDE_M * np.array([modes[mode - 1].shape(x) for x in s]))
    res = B.integrate(bs.model, bs.y0, bs.t_out_s, method="radau5")
    rel, _ = bs.model.relative_nodes(res.y)
    w = bs.model.node_masses()
    z_nodes = rel @ bs.normal
    z_nodes = z_nodes - (z_nodes @ w)[:, None] / w.sum()
    return _modal_frequency(res.t, s, z_nodes, w, modes, mode, ph["omega"], n) / ph["omega"]


def lateral_references(mode: int) -> dict:
    ph = _physics(tension_scene())
    modes = lateral_modes(mode)
    s = np.linspace(0.0, ph["L"], 2001)
    t_mean = float(np.mean(C.hill_tension_profile(s, ph["m0"], ph["mf"], ph["mt"], ph["L"], ph["omega"])))
    uniform = C.uniform_string_frequency(mode, ph["L"], t_mean, ph["mt"] / ph["L"])
    return {"continuum": modes[mode - 1].omega_rad_s / ph["omega"], "uniform_string": uniform / ph["omega"]}


def _normal(scene):
    r, v = scene.reference_state()
    z = np.cross(r, v)
    return z / np.linalg.norm(z)


# ---------------------------------------------------------------------------------------------
# the sweep and its report
# ---------------------------------------------------------------------------------------------
def observed_orders(values):
    """Observed order from three successive doublings: log2((v1 - v2)/(v2 - v3)), NaN before."""
    v = np.asarray(values, float)
    out = [math.nan, math.nan]
    for i in range(2, len(v)):
        a, b = v[i - 2] - v[i - 1], v[i - 1] - v[i]
        out.append(math.log2(a / b) if a * b > 0 else math.nan)
    return out


def richardson(h, values, order=2.0):
    """Converged-value estimate from the two finest values at mesh sizes h (h ~ segment length):
    v* = v2 + (v2 - v1) h2^p/(h1^p - h2^p)."""
    ok = [(x, v) for x, v in zip(h, values) if not math.isnan(v)]
    if len(ok) < 2:
        return math.nan
    (h1, v1), (h2, v2) = ok[-2], ok[-1]
    return v2 + (v2 - v1) * h2**order / (h1**order - h2**order)


def run_sweep(counts=COUNTS, log=print):
    import pandas as pd

    rows = []

    def add(quantity, unit, model, n, value, ref, ref_name):
        rows.append(dict(quantity=quantity, unit=unit, model=model, n=n, value=value, reference=ref,
                         reference_name=ref_name, rel_err=(value - ref) / ref))  # fmt: skip

    t0 = time.perf_counter()
    lib_ref = libration_reference()
    tref = tension_references()
    lat_refs = {k: lateral_references(k) for k in (1, 2)}
    for n in counts:
        for model, fn in (("tmed", libration_tmed), ("bead", libration_bead)):
            add("libration_inplane", "omega", model, n, fn(n), lib_ref, "rigid dumbbell, elliptic K")
        for model, fn in (("tmed", tension_tmed), ("bead", tension_bead)):
            t_root, t_tip = fn(n)
            add("tension_root", "N", model, n, t_root, tref["exact"][0], "exact continuous, 1/r^2")
            add("tension_tip", "N", model, n, t_tip, tref["exact"][1], "exact continuous, 1/r^2")
        for k in (1, 2):
            for model, fn in (("tmed", lateral_tmed), ("bead", lateral_bead)):
                add(f"lateral_oop_{k}", "omega", model, n, fn(n, k), lat_refs[k]["continuum"], "continuous string, T(s), Hill")
        log(f"n = {n} done ({time.perf_counter() - t0:.0f} s)")
    df = pd.DataFrame(rows)
    # Observed orders against the finest value of each model; differences between the models.
    # Observed orders (three successive counts) and Richardson estimates with the mesh size of
    # each model: a TMED rod is L/n long, a bead segment L/(n + 1).
    df["order"] = math.nan
    df["richardson"] = math.nan
    for (q, m), g in df.groupby(["quantity", "model"]):
        g = g.sort_values("n")
        df.loc[g.index, "order"] = observed_orders(list(g["value"]))
        h = [1.0 / n if m == "tmed" else 1.0 / (n + 1) for n in g["n"]]
        df.loc[g.index, "richardson"] = richardson(h, list(g["value"]))
    piv = df.pivot_table(index=["quantity", "n"], columns="model", values="value", dropna=False)
    diff = ((piv["bead"] - piv["tmed"]) / piv["tmed"]).rename("bead_minus_tmed_rel")
    df = df.merge(diff.reset_index(), on=["quantity", "n"], how="left")
    return df, tref, lat_refs, lib_ref


def write_report(df, tref, lat_refs, lib_ref, out: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "bead_vs_tmed.csv", index=False, float_format="%.12g")
    qs = ["libration_inplane", "tension_root", "tension_tip", "lateral_oop_1", "lateral_oop_2"]
    fig, axes = plt.subplots(1, len(qs), figsize=(4 * len(qs), 3.6))
    for ax, q in zip(axes, qs):
        for model, mk in (("tmed", "o-"), ("bead", "s--")):
            g = df[(df.quantity == q) & (df.model == model)].sort_values("n")
            ax.loglog(g["n"], np.abs(g["rel_err"]), mk, label=model)
        g = df[(df.quantity == q) & (df.model == "bead")].sort_values("n")
        ax.loglog(g["n"], np.abs(g["bead_minus_tmed_rel"]), "k:", label="|bead - tmed|/tmed")
        ax.set_title(q, fontsize=9)
        ax.set_xlabel("n (rods / interior beads)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("|relative error vs reference|")
    axes[0].legend(fontsize=7)
    from tetherlab.provenance import stamp_figure
    stamp_figure(fig, "studies/bead_vs_tmed.py; lumped-mass oracle tetherlab/oracles/bead.py")
    fig.savefig(out / "bead_vs_tmed.png", dpi=120)
    plt.close(fig)

    lines = ["## Bead (lumped-mass) model against TMED", "",
             "Generated by `studies/bead_vs_tmed.py`; derivations in `docs/bead.md`. "
             "rel_err: against the reference named in the table; order: observed order from three "
             "successive counts; bead-tmed: relative difference of the two models; Richardson: "
             "order-2 extrapolation from the two finest counts (mesh L/n for TMED, L/(n+1) for beads).", "",
             f"References: libration sqrt(3) omega x pi/(2K(sin^2 theta0)) = {lib_ref:.8f} omega "
             f"(theta0 = {THETA0_RAD} rad); exact tension root {tref['exact'][0]:.10f} N, tip {tref['exact'][1]:.10f} N "
             f"(Hill closed form {tref['hill'][0]:.6f} N, {tref['hill'][1]:.6f} N); lateral out-of-plane continuum "
             f"{lat_refs[1]['continuum']:.6f}, {lat_refs[2]['continuum']:.6f} omega (uniform string "
             f"{lat_refs[1]['uniform_string']:.6f}, {lat_refs[2]['uniform_string']:.6f} omega).", "",
             "| quantity | n | tmed | rel_err | order | bead | rel_err | order | bead-tmed |",
             "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for q in qs:
        for n in sorted(df.n.unique()):
            t = df[(df.quantity == q) & (df.model == "tmed") & (df.n == n)].iloc[0]
            b = df[(df.quantity == q) & (df.model == "bead") & (df.n == n)].iloc[0]
            lines.append(f"| {q} | {n} | {t.value:.10g} | {t.rel_err:.2e} | {t.order:.2f} | "
                         f"{b.value:.10g} | {b.rel_err:.2e} | {b.order:.2f} | {b.bead_minus_tmed_rel:.2e} |")  # fmt: skip
    lines += ["", "| quantity | reference | TMED Richardson | bead Richardson | bead-tmed (Richardson) | TMED R. vs reference |",
              "|---|---|---|---|---|---|"]
    for q in qs:
        t = df[(df.quantity == q) & (df.model == "tmed")].iloc[0]
        b = df[(df.quantity == q) & (df.model == "bead")].iloc[0]
        lines.append(f"| {q} | {t.reference:.10g} | {t.richardson:.10g} | {b.richardson:.10g} | "
                     f"{(b.richardson - t.richardson) / t.richardson:.2e} | {(t.richardson - t.reference) / t.reference:.2e} |")  # fmt: skip
    lines += ["", "![bead vs tmed](bead_vs_tmed.png)", ""]
    (out / "bead_vs_tmed.md").write_text("\n".join(lines).replace("nan", "—"))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir", type=Path)
    ap.add_argument("--counts", type=int, nargs="+", default=list(COUNTS))
    args = ap.parse_args(argv)
    df, tref, lat, lib = run_sweep(tuple(args.counts))
    write_report(df, tref, lat, lib, args.outdir)
    print((args.outdir / "bead_vs_tmed.md").read_text())


if __name__ == "__main__":
    main()
