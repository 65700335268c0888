"""``make verify``: run every oracle comparison and study, write reports/, enforce the gates.

Gates live in references/gates.toml (quantity, threshold, unit, source).  Each check below
measures one gate's value; the report lists every measurement with pass/fail, the figures of the
paper's section 4.3 cases, and a footer with commit, versions, machine and date.  The exit status
is non-zero when any gate fails.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from .report import _fmt as _report_fmt
from .report import table as _report_table

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "studies" / "scenes"
MU_EARTH = 3.986004418e14  # the "earth" preset of tetherlab/scene.py


def _libration_frequency_errors(ns, rows_out):
    """|frequency / theory - 1| for in- and out-of-plane libration, one run per n and plane."""
    from .diagnostics import zero_crossing_frequency
    from .pipeline import simulate
    from .scene import load_scene

    err = {}
    for plane in ("in", "out"):
        for n in ns:
            sc = load_scene(SCENES / "libration-inplane.toml").replace(
                **{
                    "tethers.main.rods": n,
                    "tethers.main.initial.theta": "0.05 rad" if plane == "in" else "0 rad",
                    "tethers.main.initial.phi": "0.05 rad" if plane == "out" else "0 rad",
                    "orbit.motion": "equilibrium",
                    "duration": "3 orbits",
                    "output.count": 3001,
                }
            )
            d = simulate(sc, progress=False).diagnostics
            w = math.sqrt(MU_EARTH / d["com_radius_m"].iloc[0] ** 3)
            col = "main.theta_rad" if plane == "in" else "main.phi_rad"
            expected = math.sqrt(3) * w if plane == "in" else 2 * w
            e = zero_crossing_frequency(d["t_s"].to_numpy(), d[col].to_numpy()) / expected - 1
            rows_out.append({"case": f"{plane}-plane libration, n={n}", "frequency/expected - 1": e})
            err[plane, n] = e
    return err


def check_libration(rows_out, ns=(1, 2, 4)):
    """Libration frequencies against rigid-dumbbell theory (sqrt3 w in plane, 2 w out of plane),
    and their spread over the rod count (the TMED's discretisation must not move them)."""
    err = _libration_frequency_errors(ns, rows_out)
    spread = max(abs(err[pl, n] - err[pl, ns[-1]]) for pl in ("in", "out") for n in ns)
    rows_out.append({"case": f"largest |f(n) - f(n={ns[-1]})| / f_theory over n = {', '.join(map(str, ns))}",
                     "frequency/expected - 1": spread})  # fmt: skip
    return {
        "libration_inplane_frequency": max(abs(err["in", n]) for n in ns),
        "libration_outofplane_frequency": max(abs(err["out", n]) for n in ns),
        "libration_rod_count_spread": spread,
    }


def check_vertical(rows_out):
    from .pipeline import simulate
    from .scene import load_scene

    worst = 0.0
    for n in (1, 2, 4):
        sc = load_scene(SCENES / "vertical-equilibrium.toml").replace(**{"tethers.main.rods": n})
        res = simulate(sc, progress=False)
        d = res.diagnostics
        m = float(max(np.abs(d["main.theta_rad"]).max(), np.abs(d["main.phi_rad"]).max()))
        nsteps = int(res.stats["n_accepted"])
        rows_out.append({"case": f"local vertical, n={n}, 10 orbits", "max angle (rad)": m, "steps": nsteps,
                         "N rtol (budget, rad)": nsteps * sc.integrator.rtol})  # fmt: skip
        worst = max(worst, m)
    return {"vertical_equilibrium": worst}


U_ROUND = 2.0**-53  # unit round-off of IEEE double


def _integrate_diag(model, y0, t_out, rtol, atol):
    """One DOP853 run of a model from y0 and its diagnostics; a failed run returns (result, None)."""
    from . import diagnostics as D
    from .formulations.cowell import cowell_rhs
    from .integrators import integrate

    r = integrate("dop853", cowell_rhs, 0.0, y0, t_out, model.fresh_params(), rtol, atol, second_order=True)
    if r.status != 0 or len(r.t) != len(t_out):
        return r, None
    return r, D.compute(model, r.t, r.y)["global"]


def _angular_momentum_internal(rows_out, quick):
    """max|dH| over 3 orbits against the round-off bound B_H of the hard cases."""
    from . import diagnostics as D
    from .pipeline import prepare
    from .scene import load_scene
    from .system import point_positions

    worst = 0.0
    cases = [("lateral-two-rods.toml", 2)] if quick else [("libration-inplane.toml", 1), ("lateral-two-rods.toml", 2),
                                                           ("libration-inplane.toml", 4)]  # fmt: skip
    for model in ("paper", "energy", "printed"):
        for base, n in cases:
            if model == "printed" and n != 2:
                continue
            sc = load_scene(SCENES / base).replace(
                **{"tethers.main.rods": n, "tethers.main.model": "energy" if model == "energy" else "paper",
                   "duration": "3 orbits", "integrator.rtol": 1e-12, "integrator.atol": 1e-12,
                   "output.count": 301}
            )  # fmt: skip
            prep = prepare(sc)
            if model == "printed":  # scenes refuse it (evidence only): the mutant switches it on
                from . import mutants

                ctx = mutants.active("eq20_printed_sign")
            else:
                import contextlib

                ctx = contextlib.nullcontext()
            with ctx:
                r, g = _integrate_diag(prep.model, prep.y0, prep.t_out, prep.rtol, prep.atol)
            label = f"{model} model, {base.removesuffix('.toml')}, n={n}, 3 orbits, rtol 1e-12"
            if g is None:
                rows_out.append({"case": label + ": run failed", "max |dH| / B_H": math.inf})
                if model != "printed":
                    worst = math.inf
                continue
            H = g[:, D.G_HX : D.G_HZ + 1]
            dH = float(np.linalg.norm(H - H[0], axis=1).max())
            # S_H = max_t sum m |r||v| over every point mass (root, tips, TMED masses)
            s_h = 0.0
            for y in r.y[:: max(1, len(r.y) // 20)]:
                pts = point_positions(prep.model, y)
                mr = prep.model.rod_masses()
                sh = prep.model.root_mass_kg * np.linalg.norm(pts["r0"]) * np.linalg.norm(pts["v0"])
                for k, t in enumerate(prep.model.tethers):
                    sh += t.tip_mass_kg * np.linalg.norm(pts["joints"][k][-1]) * np.linalg.norm(pts["jvel"][k][-1])
                for i in range(prep.model.n_rods):
                    for sgn in (-1.0, 1.0):
                        sh += 0.5 * mr[i] * np.linalg.norm(pts["rG"][i] + sgn * pts["d"][i]) * np.linalg.norm(
                            pts["vG"][i] + sgn * pts["dd"][i])
                s_h = max(s_h, sh)
            nsteps = int(r.stats["n_accepted"])
            b_h = 4.0 * (2.0 / math.sqrt(3.0)) * U_ROUND * math.sqrt(nsteps) * s_h
            h_int = D.internal_angular_momentum_scale(prep.model, prep.y0)
            ratio = dH / b_h
            if model == "printed":
                label += " (negative control: eq. 20 as printed must fail)"
            rows_out.append({"case": label, "max |dH| / |H|": dH / float(np.linalg.norm(H[0])),
                             "max |dH| / H_internal": dH / h_int, "B_H / H_internal": b_h / h_int,
                             "max |dH| / B_H": ratio, "steps": nsteps})  # fmt: skip
            if model != "printed":
                worst = max(worst, ratio)
    return worst


def free_space_case(kind: str, n: int, damping_n_s: float = 0.0):
    """docs/model.md 6.3's free-space scenario (studies/model_properties.py free_case): root 50 kg,
    tip 20 kg, 100 m tether of 5 kg, EA 1 kN, rods bent out of line, translating and spinning,
    1 % initial stretch (5 J), rod masses 1 : 1.5 : 2 : 2.5; optionally damped."""
    from .model.params import ParamView
    from .system import TetherSpec, build_model, chain_state

    m = build_model(root_mass_kg=50.0, tethers=[TetherSpec("t", n, 100.0, 1e3, 5.0, damping_n_s, kind, 20.0, "tip")],
                    effects=[], central={})  # fmt: skip
    w = np.array([1.0, 1.5, 2.0, 2.5])[:n]
    ParamView(m.p).rods.mass_kg = 5.0 * w / w.sum()
    dirs = np.array([[1, 0, 0], [0.8, 0.6, 0], [0.6, 0.8, 0.1], [0.3, 0.9, 0.3]][:n], float)
    y0 = chain_state(m, np.zeros(3), np.array([0.3, -0.2, 0.1]), [dirs], [0.01], np.array([0.0, 0.02, 0.05]))
    return m, y0


ENERGY_RTOL = 1e-12


def _energy_free_space(rows_out, quick):
    """max|dE| / max V_e of the energy model in free space (docs/model.md 6.3 table B), paper model
    beside it as the control it must separate."""
    from . import diagnostics as D

    worst = 0.0
    for kind in ("energy", "paper"):
        for n in (2,) if quick else (1, 2, 4):
            m, y0 = free_space_case(kind, n)
            r, g = _integrate_diag(m, y0, np.linspace(0.0, 500.0, 501), ENERGY_RTOL, ENERGY_RTOL)
            label = f"{kind} model, free space, n={n}, 500 s, rtol {ENERGY_RTOL:g}"
            if g is None:
                rows_out.append({"case": label + ": run failed", "max |dE| / max V_e": math.inf})
                worst = math.inf if kind == "energy" else worst
                continue
            de = float(np.abs(g[:, D.G_E] - g[0, D.G_E]).max())
            ve = float(g[:, D.G_VE].max())
            s_e = float((2.0 * g[:, D.G_KE] + g[:, D.G_VE]).max())
            nsteps = int(r.stats["n_accepted"])
            budget = nsteps * ENERGY_RTOL * s_e / ve if ve > 0 else math.inf
            value = de / ve if ve > 0 else math.inf
            if kind == "paper":
                label += " (control: the paper model does not conserve E, docs/model.md 6.2; must fail)"
            rows_out.append({"case": label, "max |dE| / max V_e": value, "N rtol S_E / max V_e (budget)": budget,
                             "steps": nsteps})  # fmt: skip
            if kind == "energy":
                worst = max(worst, value)
    return worst


POWER_DAMPING_N_S = 20.0


def _power_balance(rows_out):
    """E(t) - E(0) + W_d(t) = 0 for the damped energy model, W_d = int sum D L_u eps'^2 dt
    (docs/model.md 6.2 with D > 0), in units of its budget."""
    from scipy.integrate import cumulative_simpson, cumulative_trapezoid

    from . import diagnostics as D

    worst = 0.0
    for kind in ("energy", "paper"):
        n = 2
        m, y0 = free_space_case(kind, n, POWER_DAMPING_N_S)
        ts = np.linspace(0.0, 100.0, 4001)
        r, g = _integrate_diag(m, y0, ts, ENERGY_RTOL, ENERGY_RTOL)
        label = f"{kind} model, free space, n={n}, D = {POWER_DAMPING_N_S:g} N s, 100 s"
        if g is None:
            rows_out.append({"case": label + f": run failed ({r.message})", "max |dE + W_d| / budget": math.inf})
            worst = math.inf if kind == "energy" else worst
            continue
        h = r.y.shape[1] // 2
        lu = m.rod_lengths()
        pw = np.zeros(len(ts))
        for i in range(n):
            d = r.y[:, 3 + 3 * i : 6 + 3 * i]
            dd = r.y[:, h + 3 + 3 * i : h + 6 + 3 * i]
            u = d / np.linalg.norm(d, axis=1)[:, None]
            epsd = 2.0 * math.sqrt(3.0) * np.einsum("ij,ij->i", u, dd) / lu[i]
            pw += POWER_DAMPING_N_S * lu[i] * epsd**2
        w_s = cumulative_simpson(pw, x=ts, initial=0.0)
        w_t = cumulative_trapezoid(pw, x=ts, initial=0.0)
        de = g[:, D.G_E] - g[0, D.G_E]
        s_e = float((2.0 * g[:, D.G_KE] + g[:, D.G_VE]).max())
        nsteps = int(r.stats["n_accepted"])
        budget = nsteps * ENERGY_RTOL * s_e + float(np.abs(w_s - w_t).max())
        value = float(np.abs(de + w_s).max()) / budget
        if kind == "paper":
            label += " (control: the paper model's E' has the extra term of docs/model.md 6.2)"
        rows_out.append({"case": label, "W_d(T) (J)": float(w_s[-1]), "E(T) - E(0) (J)": float(de[-1]),
                         "max |dE + W_d| / budget": value, "budget (J)": budget})  # fmt: skip
        if kind == "energy":
            worst = max(worst, value)
    return worst


def check_invariants(rows_out, quick=False):
    """Angular momentum against its round-off bound (paper, energy; printed eq. 20 as control),
    the energy model's energy against the elastic energy in free space, and its power balance
    with damping."""
    return {
        "angular_momentum_internal": _angular_momentum_internal(rows_out, quick),
        "energy_model_energy": _energy_free_space(rows_out, quick),
        "energy_model_power_balance": _power_balance(rows_out),
    }


def check_lateral_mode(rows_out, kinds=("paper", "energy", "printed")):
    """The two-rod lateral (second) in-plane libration mode against the rigid-link chain.

    The single-rod sqrt(3) w and 2 w frequencies cannot see the eq. 20 sign (a lone rod's
    transverse inertia does not enter them); the lateral mode of two rods does.  Uses the study
    studies/model_properties.py (part E), whose reference is docs/model.md section 9.
    """
    from . import mutants

    mp = _load_study("model_properties")
    (win, vin), _ = mp.rigid_chain_modes()
    worst = 0.0
    for kind in kinds:
        import contextlib

        ctx = mutants.active("eq20_printed_sign") if kind == "printed" else contextlib.nullcontext()
        with ctx:
            try:
                ts, ang = mp.libration_run("paper" if kind == "printed" else kind, vin[:, 1], "in")
            except RuntimeError as exc:
                rows_out.append({"case": f"{kind} model: run failed ({exc})", "|w/w_ref - 1|": math.inf})
                worst = math.inf if kind != "printed" else worst
                continue
        eta = (vin.T @ mp._mass_matrix() @ ang)[1]
        w, _ = mp.dominant_frequency(ts, eta)
        err = abs((w / mp.OMEGA) / win[1] - 1.0)
        label = f"{kind} model: lateral mode {w / mp.OMEGA:.4f} w vs rigid-link chain {win[1]:.4f} w"
        if kind == "printed":
            label += " (negative control)"
        rows_out.append({"case": label, "|w/w_ref - 1|": err})
        if kind != "printed":
            worst = max(worst, err)
    return {"lateral_mode_two_rods": worst}


HEYOKA_ORBITS = ROOT / "references" / "heyoka_orbits" / "references.json"


def check_heyoka_orbits(rows_out):
    """Point-mass orbits with J2 and J2-J4 against heyoka's binary128 references (1 day of LEO),
    integrated now: the largest position error at the reference's output times."""
    from .pipeline import simulate
    from .scene import Scene

    ref = json.loads(HEYOKA_ORBITS.read_text())
    worst = 0.0
    for case, effects in (("leo_j2", {"central_gravity": {}, "j2": {}}),
                          ("leo_zonal", {"central_gravity": {}, "zonal": {}})):  # fmt: skip
        c = ref["cases"][case]
        states = np.array(c["states_float"])
        t = np.array(c["t_s"])
        scene = Scene.from_dict({
            "name": f"heyoka-{case}", "duration": f"{c['duration_days']} d", "effects": effects,
            "bodies": {"sat": {"mass": "100 kg", "position": [f"{float(v)!r} m" for v in states[0, :3]],
                               "velocity": [f"{float(v)!r} m/s" for v in states[0, 3:]]}},
            "integrator": {"method": "dop853", "rtol": 1e-13, "atol": 1e-13},
            "output": {"count": len(t)},
        })  # fmt: skip
        ts = simulate(scene, progress=False).timeseries
        pos = ts[["sat.x_m", "sat.y_m", "sat.z_m"]].to_numpy()
        err = float(np.linalg.norm(pos - states[:, :3], axis=1).max())
        rows_out.append({"case": f"{case} ({', '.join(effects)}), 1 day, dop853 rtol 1e-13 vs heyoka binary128",
                         "max position error (m)": err})  # fmt: skip
        worst = max(worst, err)
    return {"heyoka_orbits_position": worst}


def check_stiefel_probe(rows_out):
    """One Cowell and one DROMO run of the Stiefel-Scheifele case (dop853, 1e-13): the cheap probe
    of the stiefel_*_best_error gates for the negative controls (the full table is the study);
    and the run of stiefel_example1_te_error."""
    out = {f"stiefel_{form}_best_error": _stiefel_error("ex2", form, "dop853", 1e-13, rows_out)
           for form in ("cowell", "dromo")}  # fmt: skip
    out["stiefel_example1_te_error"] = _stiefel_error("ex1", *EXAMPLE1_TE_RUN, rows_out)
    return out


#: the gate stiefel_example1_te_error's run (docs/dromo.md section 11): Example 1 (J2 only) in the
#: DROMO sigma form with the linear time element, ABM, tolerance 1e-11 (measured 3.5 cm)
EXAMPLE1_TE_RUN = ("dromo+te", "abm", 1e-11)


def _stiefel_error(case: str, form: str, method: str, tol: float, rows_out) -> float:
    """Final position error (m) of one Stiefel-Scheifele run against the case's reference; a
    failed run is an infinite error (it fails the gate)."""
    from .benchmarks.stiefel import reference_position_m, runner

    label = f"Stiefel-Scheifele{' Example 1' if case == 'ex1' else ''}, {form}, {method} {tol:g}"
    try:
        r, _ = runner(form, method, tol, case)()
        err = float(np.linalg.norm(r - reference_position_m(case)))
    except Exception as exc:
        err = math.inf
        rows_out.append({"case": f"{label}: failed: {exc}"})
    rows_out.append({"case": label, "final position error (m)": err})
    return err


DE421_EPOCH = "2026-01-01T00:00:00"


def check_de421(rows_out):
    """The Chebyshev fit of DE421 (ephemeris.fit_block, as the moon_de421/sun_de421 effects use
    it) against skyfield between the fit nodes, 30 days from 2026-01-01 TDB."""
    from . import ephemeris

    worst = 0.0
    for body in ephemeris.DE421_BODIES:
        pos = ephemeris.de421_position_function(body, DE421_EPOCH)
        try:
            _, err = ephemeris.fit_block(pos, 30 * 86400.0)
        finally:
            pos.close()
        rows_out.append({"case": f"{body}: degree {ephemeris.DEGREE}, {ephemeris.SEGMENT_S / 86400:g}-day segments, 30 days",
                         "largest fit error vs skyfield (m)": err})  # fmt: skip
        worst = max(worst, err)
    return {"de421_fit_error": worst}


DOP_TOLS = tuple(10.0**-k for k in range(5, 14))


def check_dop853(rows_out):
    """Steps of DOP853 against the tolerance on a Kepler orbit (e = 0.1, 5 orbits): the slope of
    log(steps) on log(1/tol) is the inverse order of the step-size control, 1/8 (Hairer's DOP853:
    h_new = h err^(-1/8))."""
    from .forces import EFFECTS
    from .formulations.cowell import cowell_rhs
    from .integrators.driver import integrate
    from .system import build_model, tolerance_scales

    m = build_model(root_mass_kg=1.0, tethers=[], effects=[(EFFECTS["central_gravity"], {})],
                    central={"mu_m3_s2": MU_EARTH, "radius_m": 6378137.0})  # fmt: skip
    a, e = 7.0e6, 0.1
    rp = a * (1 - e)
    y0 = np.array([rp, 0.0, 0.0, 0.0, math.sqrt(MU_EARTH * (1 + e) / rp), 0.0])
    period = 2 * math.pi * math.sqrt(a**3 / MU_EARTH)
    steps = []
    for tol in DOP_TOLS:
        atol = tol * tolerance_scales(m, a, math.sqrt(a**3 / MU_EARTH))
        r = integrate("dop853", cowell_rhs, 0.0, y0.copy(), np.array([0.0, 5 * period]), m.fresh_params(), tol, atol)
        err = float(np.linalg.norm(r.y[-1, :3] - y0[:3]))  # back at periapsis (Kepler)
        steps.append(r.stats["n_accepted"])
        rows_out.append({"case": f"Kepler e = 0.1, 5 orbits, tol {tol:.0e}", "steps": r.stats["n_accepted"],
                         "position error at 5 T (m)": err})  # fmt: skip
    slope = float(np.polyfit(np.log(1.0 / np.array(DOP_TOLS)), np.log(steps), 1)[0])
    rows_out.append({"case": "slope of log(steps) on log(1/tol) (expected 1/8)", "steps": slope})
    return {"dop853_work_exponent": abs(slope - 0.125)}


def check_reproducible(rows_out):
    """Two runs of the same scene in this process give bit-identical numbers (fixed seeds, no
    wall-clock-dependent chunking: the driver chunks by steps and resumes exactly)."""
    from .pipeline import simulate
    from .scene import load_scene

    worst = 0.0
    for name in ("bench-libration", "hard-slack-snap"):
        sc = load_scene(SCENES / f"{name}.toml")
        if name == "hard-slack-snap":
            sc = sc.replace(**{"duration": "200 s"})
        a = simulate(sc, progress=False).timeseries.to_numpy()
        b = simulate(sc, progress=False).timeseries.to_numpy()
        diff = float(np.nanmax(np.abs(a - b))) if a.shape == b.shape else math.inf
        rows_out.append({"case": f"{name}: two runs, largest difference of any output", "value": diff,
                         "identical": bool(diff == 0.0)})  # fmt: skip
        worst = max(worst, diff)
    return {"reproducible_runs": worst}


def check_stiefel_reference(rows_out):
    """Data check of references/stiefel/reference.json: the builder's distance between its two
    independent references (heyoka real128, decimal Taylor), read, not recomputed."""
    ref = json.loads((ROOT / "references" / "stiefel" / "reference.json").read_text())
    # the stored decimal strings stop where the two methods stop agreeing (2e-22 m), so the
    # builder's own full-precision distance is the measurement here
    a = np.array([float(x) for x in ref["final_state"]["position_km"]])
    dist = float(ref["second_method"]["distance_to_reference_m"])
    pub = np.array([float(x) for x in ref["published"]["position_km"]])
    rows_out.append({"case": "Stiefel-Scheifele: heyoka real128 vs decimal Taylor", "distance (m)": dist})
    rows_out.append({"case": "Stiefel-Scheifele: reference vs published (paper eq. 52)",
                     "distance (m)": float(np.linalg.norm(a - pub) * 1e3)})
    # a data check, not a measurement: nothing is integrated here (the two references were built
    # by references/stiefel/build_reference.py); the measurement against them is the Stiefel study
    return {"stiefel_reference_data_check": dist}


def section_43_figures(out: Path, rows_out):
    """Run the paper's section 4.3 scenes and draw their libration figures (paper Figs. 5-6)."""
    from .plots import plot_run
    from .scene import load_scene
    from .pipeline import simulate

    figs = []
    for name in ("libration-inplane", "libration-outofplane", "lateral-two-rods", "vertical-equilibrium"):
        res = simulate(load_scene(SCENES / f"{name}.toml"), progress=False)
        run_dir = out / "runs" / name
        res.save(run_dir)
        files = plot_run(run_dir)
        figs.append((name, [f.relative_to(out) for f in files]))
        rows_out.append({"case": name, "steps": res.stats["n_accepted"], "rhs": res.stats["n_rhs"],
                         "wall (s)": res.stats["wall_s"]})
    return figs


# -- studies: scripts in studies/ that write OUTDIR/<name>.md (+ CSV, PNG) ------------------------
def _load_study(name: str):
    import importlib.util

    path = ROOT / "studies" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"tetherlab_study_{name}", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses (and pickling) look their module up there
    spec.loader.exec_module(mod)
    return mod


def catenary_values(df, rows_out=None) -> dict:
    """The catenary gates from the study's table (paper model): the n = 64 errors in units of
    their Richardson estimate |e(32) - e(64)| / (2^2 - 1) (order 2, docs/catenary.md), and the
    observed order."""
    mod = _load_study("catenary")
    paper = df[df.model == "paper"].sort_values("n")
    last, prev = paper.iloc[-1], paper.iloc[-2]
    def worst(cols):
        w = 0.0
        for c in cols:
            est = abs(float(prev[c]) - float(last[c])) / 3.0
            ratio = float(last[c]) / est if est > 0 else math.inf
            if rows_out is not None:
                rows_out.append({"case": f"catenary {c}, n = {int(last.n)} (paper model)", "error": float(last[c]),
                                 "Richardson estimate |e(n/2) - e(n)|/3": est, "error / estimate": ratio})  # fmt: skip
            w = max(w, ratio)
        return w

    out = {
        "catenary_shape_n64": worst(("shape_joints_m",)),
        "catenary_tension_n64": worst(("tension_A_N", "tension_B_N", "holding_force_N", "nail_force_N")),
    }
    order = mod.observed_order(paper["n"], paper["shape_joints_m"])
    out["catenary_order_deviation"] = abs(order - 2.0)
    return out


def _catenary_gates(outdir: Path) -> dict:
    import pandas as pd

    return catenary_values(pd.read_csv(outdir / "catenary.csv"))


def check_catenary_probe(rows_out):
    """The catenary study's paper-model rows n = 4 ... 64 (its gates), without figures."""
    import pandas as pd

    mod = _load_study("catenary")
    df = pd.DataFrame(mod.run(mod.load_reference(), ns=(4, 8, 16, 32, 64), models=("paper",)))
    return catenary_values(df, rows_out)


def _stiefel_gates(outdir: Path) -> dict:
    import pandas as pd

    df = pd.read_csv(outdir / "stiefel_table.csv")
    best = {who: float(g["final_position_error_m"].min()) for who, g in df.groupby("who")}
    form, method, tol = EXAMPLE1_TE_RUN
    ex1 = df[(df["who"] == f"ex1 tetherlab {form} {method}") & (np.isclose(df["tol"], tol, rtol=1e-9, atol=0.0))]
    return {
        "stiefel_cowell_best_error": min(v for k, v in best.items() if k.startswith("tetherlab cowell")),
        "stiefel_dromo_best_error": min(v for k, v in best.items() if k.startswith("tetherlab dromo")),
        # a missing row (the study did not run it) fails the gate
        "stiefel_example1_te_error": float(ex1["final_position_error_m"].iloc[0]) if len(ex1) else math.inf,
    }


def _deorbit_gates(outdir: Path) -> dict:
    runs = json.loads((outdir / "deorbit_summary.json").read_text())["runs"]
    n1 = runs[0]
    out = {"deorbit_n1_vs_paper": abs(n1["vs_paper_rel"]), "deorbit_n1_vs_closed_form": abs(n1["vs_closed_form_rel"])}
    n4 = [r for r in runs if r.get("label", "").startswith("n=4")]
    if n4:
        out["deorbit_n4_vs_n1"] = abs(n4[0]["deorbit_days"] / n1["deorbit_days"] - 1.0)
    return out


def _hard_cases_gates(outdir: Path) -> dict:
    s = json.loads((outdir / "hard_cases_summary.json").read_text())
    control = s.get("negative_control_over_bound")
    return {
        "hard_cases_failed": float(s["failed"]),
        "hard_cases_invariant_over_bound": s["invariant_over_bound"],
        "hard_cases_convergence_score": s["convergence_score"],
        "hard_cases_floor_over_loose_change": s["floor_over_loose_change"],
        "hard_cases_collapse_stop_spread": s["stop_time_spread_s"],
        # the control must exceed its bound; the gate reads bound / measured (<= 1 passes)
        "hard_cases_negative_control": (1.0 / control) if control else math.inf,
        # issue 11: n = 512 over an orbit (part 5), and its anti-damped control (inverted likewise)
        "hard_cases_n512_stability": s["n512_stability"] if s.get("n512_stability") is not None else math.inf,
        "hard_cases_n512_negative_control": _inverse(s.get("n512_control_stability")),
    }


def _inverse(v):
    """1 / a control's measurement (its gate passes when the control fails its bound); a control
    that did not run gives inf (fails), one that stopped (inf) gives 0."""
    return math.inf if v is None or v == 0 else 1.0 / v


def _rigid_bodies_gates(outdir: Path) -> dict:
    """Gates of studies/rigid_bodies.py (issue 10; bounds in docs/rigid-oracles.md section 7).
    A part the build cannot run (no rigid bodies) leaves its gates None: "not measured"."""
    g = json.loads((outdir / "rigid_bodies_summary.json").read_text())["gates"]
    return {
        "hub_spoke_centre_tip_over_bound": g.get("hub_spoke_centre_tip_over_bound"),
        "hub_spoke_centre_tension_over_bound": g.get("hub_spoke_centre_tension_over_bound"),
        "hub_spoke_centre_order_deficit": g.get("hub_spoke_centre_order_deficit"),
        "hub_spoke_centre_negative_control": g.get("hub_spoke_centre_negative_control"),
        "hub_spoke_radius_tip_over_bound": g.get("hub_spoke_radius_tip_over_bound"),
        "hub_spoke_radius_tension_over_bound": g.get("hub_spoke_radius_tension_over_bound"),
        "hub_spoke_radius_order_deficit": g.get("hub_spoke_radius_order_deficit"),
        "hub_spoke_radius_defects_negative_control": g.get("hub_spoke_radius_defects_negative_control"),
        "torque_free_over_bound": g.get("torque_free_over_bound"),
        "torque_free_negative_control": g.get("torque_free_negative_control"),
        "torque_free_convergence": g.get("torque_free_convergence"),
        "gg_libration_frequency": g.get("gg_libration_frequency"),
        "gg_libration_negative_control": g.get("gg_libration_negative_control"),
        "wheel_exchange_over_bound": g.get("wheel_exchange_over_bound"),
        "wheels_tumbling_over_bound": g.get("wheels_tumbling_over_bound"),
        "untethered_bodies_over_bound": g.get("untethered_bodies_over_bound"),
        "conservation_tree_over_bound": g.get("conservation_tree_over_bound"),
    }


#: (title, study script in studies/, its arguments after OUTDIR, markdown it writes, gate reader)
STUDIES = [
    ("Catenary against Irvine's elastic catenary (paper section 4.2)", "catenary", [], "catenary.md", _catenary_gates),
    ("Stiefel-Scheifele: Cowell and DROMO against the oracle (paper section 4.1, Figure 3)", "stiefel_table", [],
     "stiefel_table.md", _stiefel_gates),
    ("Electrodynamic de-orbit (paper section 5, Figure 7)", "deorbit", [], None, _deorbit_gates),
    ("Lumped-mass (bead) model against TMED", "bead_vs_tmed", [], "bead_vs_tmed.md", None),
    ("Rod-count convergence", "convergence", ["--quiet"], "convergence.md", None),
    ("What accuracy costs in time (work-precision)", "workprecision", ["--quiet"], "work_precision.md", None),
    ("Hard cases", "hard_cases", ["--quiet"], "hard_cases.md", _hard_cases_gates),
    ("Fidelity ladder: the de-orbit at each environment level (issue 13)", "fidelity", ["--quiet"], "fidelity.md", None),
    ("Rigid bodies, wheels, attitude control and tether trees (issue 10)", "rigid_scenes", [], "rigid_scenes.md", None),
    ("Rigid bodies, wheels and hub-and-spoke against the oracles (issue 10)", "rigid_bodies", ["--quiet"],
     "rigid_bodies.md", _rigid_bodies_gates),
]


#: the studies that run their scenes through tetherlab.sweep (they take ``--workers N``)
SWEEPING_STUDIES = ("convergence", "workprecision", "hard_cases")


def _cores() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def _summary_md(name: str, sdir: Path) -> str:
    """A section for a study that writes JSON/CSV and figures but no Markdown of its own."""
    lines = []
    for csv in sorted(sdir.glob("*.csv")):
        import pandas as pd

        df = pd.read_csv(csv)
        keep = [c for c in df.columns if df[c].dtype != object or c in ("label", "case", "method")][:12]
        lines += [f"`{csv.name}`:", "", _table_md(df[keep].to_dict("records")), ""]
    lines += [f"![{png.stem}]({png.name})" for png in sorted(sdir.glob("*.png"))]
    return "\n".join(lines)


def run_studies(out: Path, only=None, study_workers: int | None = None):
    """Run every study into out/<name>/; a study that fails is reported (its gates then fail),
    the others still run.  ``study_workers``: the worker processes of the studies that sweep
    (``--workers``; None: their default, all cores)."""
    sections, values, failures = [], {}, []
    for title, name, extra, md_name, gates_fn in STUDIES:
        if only is not None and name not in only:
            continue
        sdir = out / name
        sdir.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        try:
            pool = ["--workers", str(study_workers)] if study_workers and name in SWEEPING_STUDIES else []
            _load_study(name).main([str(sdir), *extra, *pool])
            values.update(gates_fn(sdir) if gates_fn else {})
            md = (sdir / md_name).read_text() if md_name else _summary_md(name, sdir)
            # images and links in the study's Markdown are relative to its own directory
            md = re.sub(r"\]\((?!https?:|#)([^)]+)\)", lambda m: f"]({name}/{m.group(1)})", md)
            md = _nest_headings(md)
            sections.append((name, title, md, time.perf_counter() - t0))
        except Exception as exc:  # report and go on: one broken study must not hide the rest
            failures.append(name)
            sections.append((name, title, f"**Study failed:** `{type(exc).__name__}: {exc}`", time.perf_counter() - t0))
    return sections, values, failures


def _nest_headings(md: str) -> str:
    """A study's Markdown under the report's own section heading: its leading title (which the
    report's heading replaces) is dropped and its other headings go one level down."""
    lines = md.lstrip("\n").split("\n")
    if lines and re.match(r"#{1,2} ", lines[0]):
        lines = lines[1:]
    return re.sub(r"^(#{1,5}) ", r"#\1 ", "\n".join(lines), flags=re.M)


# one Markdown table writer for the studies' summaries and the report (tetherlab/report.py)
_table_md = _report_table
_fmt = _report_fmt


# -- negative controls: every defect of tetherlab.mutants against the gates' cheap probes -----------
#: (probe name, function(rows) -> {gate: value}, code paths it exercises)
PROBES = [
    ("libration", lambda rows: check_libration(rows, ns=(1, 4)), {"tether", "integrator"}),
    ("invariants", lambda rows: check_invariants(rows, quick=True), {"tether", "diagnostics", "integrator"}),
    ("lateral", lambda rows: check_lateral_mode(rows, kinds=("paper", "energy")), {"tether", "integrator"}),
    ("catenary", lambda rows: check_catenary_probe(rows), {"tether", "statics"}),
    ("heyoka_orbits", lambda rows: check_heyoka_orbits(rows), {"gravity", "integrator"}),
    ("stiefel", lambda rows: check_stiefel_probe(rows), {"gravity", "moon", "integrator", "dromo"}),
    ("de421", lambda rows: check_de421(rows), {"de421"}),
    ("dop853", lambda rows: check_dop853(rows), {"integrator"}),
]
#: the probes the CI test runs (tests/test_gates.py): the cheapest defect/gate pairs
FAST_PAIRS = (
    ("statics_holding_force_1pc", "catenary"),
    ("energy_without_elastic_term", "invariants"),
    ("de421_low_degree", "de421"),
    ("j2_sign", "heyoka_orbits"),
)

#: gates no defect of tetherlab.mutants can reach, and why (the report marks them toothless)
TOOTHLESS = {
    "vertical_equilibrium": "the start is the model's own relative equilibrium, solved with the same kernels, so a "
    "defect of the model moves the equilibrium with it; the gate checks the equilibrium solver and the "
    "integration's stability, not the physics",
    "reproducible_runs": "a deterministic defect is reproduced exactly; the gate guards non-determinism (chunking, "
    "threads, uninitialised memory), which no defect here introduces",
    "stiefel_reference_data_check": "a data check: it reads the builders' stored distance between two oracle "
    "references, so no simulator defect can move it",
    "catenary_order_deviation": "the statics' convergence order: the defects on the statics path are a constant "
    "offset (holding force: seen by catenary_tension_n64) or act on motion only (velocities are zero at rest)",
    "libration_outofplane_frequency": "held to the theory's leading order only (2e-3, gates.toml): the registry's "
    "defects of the distributed forces move 2 w by 1.3e-3 (F_TP dropped) and 1.7e-3 (one node) on this scene's "
    "10 kg tether between 1100 kg of end masses, inside the theory's own error; libration_rod_count_spread, "
    "which is exact to (L/r0)^2, catches both",
    "catenary_shape_n64": "the shape of a chain at rest in uniform gravity: the half-rod loads are uniform "
    "(exact for any node count) and at rest the defects of eqs. 19, 20 and F_TP change no equilibrium "
    "(measured: shape unchanged to 1e-9 under each); the statics defect in the registry is in the holding "
    "force, which catenary_tension_n64 catches",
    "deorbit_n1_vs_paper": "not probed: a de-orbit run takes minutes (the whole study in make verify); no defect of "
    "the electrodynamic or drag path is in the registry yet",
    "deorbit_n1_vs_closed_form": "not probed: as deorbit_n1_vs_paper",
    "deorbit_n4_vs_n1": "not probed: as deorbit_n1_vs_paper",
    "hard_cases_failed": "not probed: each hard case runs tens of seconds; the study runs its own eq. 20 control "
    "(hard_cases_negative_control)",
    "hard_cases_invariant_over_bound": "not probed: as hard_cases_failed (the control is the printed-model run)",
    "hard_cases_convergence_score": "not probed: as hard_cases_failed",
    "hard_cases_floor_over_loose_change": "not probed: a property of the tolerance ladders chosen, not of the code",
    "hard_cases_collapse_stop_spread": "not probed: as hard_cases_failed",
    "hub_spoke_centre_tip_over_bound": "not probed: the rigid-body study runs minutes; the registry has no defect "
    "on a point-mass hub's steady spin that the cheap probes miss, and the study's own control (a 1 % stiffer "
    "tether, hub_spoke_centre_negative_control) shows the order gate sees a stiffness error",
    "hub_spoke_centre_tension_over_bound": "not probed: as hub_spoke_centre_tip_over_bound",
    "hub_spoke_centre_order_deficit": "not probed by the registry: its own control is "
    "hub_spoke_centre_negative_control (a 1 % stiffer tether fails it)",
    "hub_spoke_centre_negative_control": "a control itself (must pass: the order gate fails a 1 % stiffer tether)",
    "hub_spoke_radius_tension_over_bound": "not probed: the rigid attachment defects are run and credited through "
    "hub_spoke_radius_tip_over_bound (the study's part B)",
    "hub_spoke_radius_order_deficit": "not probed: as hub_spoke_radius_tension_over_bound",
    "torque_free_over_bound": "not probed by the registry (no defect of the attitude kinematics in it yet): the "
    "study's own control perturbs the inertia by 1e-4 (torque_free_negative_control)",
    "torque_free_negative_control": "a control itself (a 1e-4 inertia error must fail torque_free_over_bound)",
    "torque_free_convergence": "not probed: the integrator's convergence on the torque-free body (a property of "
    "the tolerance ladder, as hard_cases_floor_over_loose_change)",
    "gg_libration_frequency": "not probed by the registry (no gravity-gradient-torque defect in it yet): the "
    "study's own control perturbs the inertia (gg_libration_negative_control)",
    "gg_libration_negative_control": "a control itself (a perturbed inertia must fail gg_libration_frequency)",
    "wheel_exchange_over_bound": "not probed: no wheel defect in the registry yet; an exact first integral "
    "(H, and energy minus motor work) within a derived round-off bound",
    "wheels_tumbling_over_bound": "not probed: as wheel_exchange_over_bound",
    "untethered_bodies_over_bound": "not probed: compares a forest against single-body runs of the same kernel; a "
    "model defect moves both alike (it guards the forest's bookkeeping)",
    "conservation_tree_over_bound": "not probed by the harness (the study runs minutes); tests/test_rigid.py runs "
    "the two attachment defects against the same first integrals and both fail them by > 1e6 x the bound",
    "mutation_uncaught_defects": "the mutation score itself",
    "mutation_toothless_unexplained": "the count of gates without teeth or reason itself",
}


def run_negative_controls(rows_out, gates: dict, names=None, probes=None):
    """Each active defect (tetherlab.mutants) against every probe on its code path.

    Returns (cells, baseline, log): cells[(defect, gate)] = (value, "caught" / "missed");
    baseline[gate] = the probe's value with no defect (a probe that fails with no defect cannot
    claim a catch).  ``names``/``probes`` restrict the run (tests)."""
    from . import mutants

    names = mutants.names() if names is None else names
    wanted = [p for p in PROBES if probes is None or p[0] in probes]
    baseline, cells = {}, {}
    t_all = time.perf_counter()
    for pname, fn, _paths in wanted:
        t0 = time.perf_counter()
        vals = fn([])
        baseline.update(vals)
        rows_out.append({"defect": "(none)", "probe": pname, "wall (s)": time.perf_counter() - t0,
                         **{g: v for g, v in vals.items()}})  # fmt: skip
    for name in names:
        m = mutants.MUTANTS[name]
        for pname, fn, paths in wanted:
            if m.path not in paths:
                continue
            if pname in m.skip:
                for g in _probe_gates(pname, baseline):
                    cells[name, g] = (None, "skipped: " + m.skip[pname])
                continue
            t0 = time.perf_counter()
            try:
                with mutants.active(name):
                    vals = fn([])
            except Exception as exc:  # a measurement that refuses to run under the defect fails it
                vals = {g: math.inf for g in _probe_gates(pname, baseline)}
                rows_out.append({"defect": name, "probe": pname, "error": f"{type(exc).__name__}: {exc}"[:200]})
            for g, v in vals.items():
                thr = gates.get(g, {}).get("threshold", math.inf)
                base_ok = not mutants.caught(baseline.get(g), thr)
                cells[name, g] = (v, "caught" if (base_ok and mutants.caught(v, thr)) else "missed")
            rows_out.append({"defect": name, "probe": pname, "wall (s)": time.perf_counter() - t0})
    rows_out.append({"defect": "(all)", "probe": "total", "wall (s)": time.perf_counter() - t_all})
    return cells, baseline


def _probe_gates(pname, baseline):
    return _PROBE_GATES.get(pname, [])


_PROBE_GATES = {
    "libration": ["libration_inplane_frequency", "libration_outofplane_frequency", "libration_rod_count_spread"],
    "invariants": ["angular_momentum_internal", "energy_model_energy", "energy_model_power_balance"],
    "lateral": ["lateral_mode_two_rods"],
    "catenary": ["catenary_shape_n64", "catenary_tension_n64", "catenary_order_deviation"],
    "heyoka_orbits": ["heyoka_orbits_position"],
    "stiefel": ["stiefel_cowell_best_error", "stiefel_dromo_best_error", "stiefel_example1_te_error"],
    "de421": ["de421_fit_error"],
    "dop853": ["dop853_work_exponent"],
}


def mutation_summary(cells, gates: dict, study_values: dict):
    """(defect -> gates that caught it, gate -> defects it caught, the two mutation gate values)."""
    from . import mutants

    by_defect = {n: [] for n in mutants.names()}
    by_gate = {g: [] for g in gates}
    for (d, g), (_v, verdict) in cells.items():
        if verdict == "caught":
            by_defect.setdefault(d, []).append(g)
            by_gate.setdefault(g, []).append(d)
    # the hard-cases study runs eq. 20 as printed itself (its control gate must pass = it was seen)
    ctrl = study_values.get("hard_cases_negative_control")
    if ctrl is not None and ctrl <= gates["hard_cases_negative_control"]["threshold"]:
        by_defect.setdefault("eq20_printed_sign", []).append("hard_cases_invariant_over_bound")
        by_gate.setdefault("hard_cases_invariant_over_bound", []).append("eq20_printed_sign")
        by_gate.setdefault("hard_cases_negative_control", []).append("eq20_printed_sign")
    # the hard-cases study runs the n = 512 tether with the damping's sign flipped (part 5): its
    # control gate passes only if the stability measure fails under that defect
    ctrl = study_values.get("hard_cases_n512_negative_control")
    if ctrl is not None and ctrl <= gates["hard_cases_n512_negative_control"]["threshold"]:
        by_defect.setdefault("damping_sign", []).append("hard_cases_n512_stability")
        by_gate.setdefault("hard_cases_n512_stability", []).append("damping_sign")
        by_gate.setdefault("hard_cases_n512_negative_control", []).append("damping_sign")
    # the rigid-body study runs the kernel's two attachment defects itself (part B): its control
    # gate passes only if the tip-radius measure fails under both (studies/rigid_bodies.py)
    ctrl = study_values.get("hub_spoke_radius_defects_negative_control")
    if ctrl is not None and ctrl <= gates["hub_spoke_radius_defects_negative_control"]["threshold"]:
        for d in ("rigid_attachment_not_rotated", "rigid_centripetal_dropped"):
            by_defect.setdefault(d, []).append("hub_spoke_radius_tip_over_bound")
            by_gate.setdefault("hub_spoke_radius_tip_over_bound", []).append(d)
            by_gate.setdefault("hub_spoke_radius_defects_negative_control", []).append(d)
    uncaught = [d for d, gs in by_defect.items() if not gs]
    unexplained = [g for g, ds in by_gate.items() if not ds and g not in TOOTHLESS]
    return by_defect, by_gate, {"mutation_uncaught_defects": float(len(uncaught)),
                                "mutation_toothless_unexplained": float(len(unexplained))}


def matrix_md(cells, gates: dict, by_defect, by_gate) -> str:
    from . import mutants

    gate_cols = [g for g in gates if any(g == gg for (_d, gg) in cells) or by_gate.get(g)]
    head = "| defect | " + " | ".join(f"[{g}](#gate-{g})" for g in gate_cols) + " | caught by |"
    lines = [head, "|---|" + "---|" * (len(gate_cols) + 1)]
    for name in mutants.names():
        row = []
        for g in gate_cols:
            v = cells.get((name, g))
            if v is None:
                row.append("CAUGHT (study)" if name in by_gate.get(g, []) else "·")
            elif v[1] == "caught":
                row.append(f"**CAUGHT** {_fmt(v[0])}")
            elif v[1].startswith("skipped"):
                row.append("skipped")
            else:
                row.append(f"missed {_fmt(v[0])}")
        lines.append(f"| {name} | " + " | ".join(row) + f" | {len(by_defect.get(name, []))} |")
    return "\n".join(lines)


# -- gate sections: where each gate's evidence is ------------------------------------------------
#: (section id, title, check function or None for a study section)
CHECKS = [
    ("libration", "Libration in circular orbit (paper section 4.3)", check_libration),
    ("vertical", "Local vertical: relative equilibrium (paper section 4.3)", check_vertical),
    ("invariants", "Invariants: angular momentum, energy, power balance (docs/model.md 6)", check_invariants),
    ("lateral", "Two-rod lateral mode (docs/model.md 9)", check_lateral_mode),
    ("gravity", "Gravity effects against heyoka (references/heyoka_orbits)", check_heyoka_orbits),
    ("de421", "DE421 Chebyshev fit (tetherlab/ephemeris.py)", check_de421),
    ("dop853", "DOP853 step-size control (Hairer, Norsett & Wanner II.4)", check_dop853),
    ("stiefel-data", "Stiefel-Scheifele references: data check (references/stiefel)", check_stiefel_reference),
    ("reproducible", "Reproducibility", check_reproducible),
]
#: figures of the section 4.3 scenes shown in the section of the gate they belong to
FIGURE_SECTION = {"libration-inplane": "libration", "libration-outofplane": "libration",
                  "lateral-two-rods": "lateral", "vertical-equilibrium": "vertical"}


def gate_section(gid: str) -> str:
    """The report section that holds a gate's figure and table."""
    for sid, _t, fn in CHECKS:
        if gid in _GATES_OF.get(sid, ()):
            return sid
    for prefix, sid in (("catenary", "study-catenary"), ("stiefel_", "study-stiefel_table"),
                        ("deorbit", "study-deorbit"), ("hard_cases", "study-hard_cases"), ("mutation", "controls")):
        if gid.startswith(prefix):
            return sid
    return "gates"


_GATES_OF = {
    "libration": ("libration_inplane_frequency", "libration_outofplane_frequency", "libration_rod_count_spread"),
    "vertical": ("vertical_equilibrium",),
    "invariants": ("angular_momentum_internal", "energy_model_energy", "energy_model_power_balance"),
    "lateral": ("lateral_mode_two_rods",),
    "gravity": ("heyoka_orbits_position",),
    "de421": ("de421_fit_error",),
    "dop853": ("dop853_work_exponent",),
    "stiefel-data": ("stiefel_reference_data_check",),
    "reproducible": ("reproducible_runs",),
}

#: gates retired, and why (kept in the report so a reader of an old report finds them)
RETIRED = {
    "angular_momentum": "relative change of |H| about the Earth's centre: |H| is almost all orbital, so the "
    "printed eq. 20 (which breaks the tether's own angular momentum) scored 6e-12 against its 1e-9. "
    "Replaced by angular_momentum_internal, the change of H against its round-off bound, which the "
    "printed model fails",
    "stiefel_reference_agreement": "renamed stiefel_reference_data_check: it reads a number the builder "
    "stored; nothing is measured when verify runs",
}


# -- running the sections: in worker processes, assembled in a fixed order ------------------------
#: measured wall time of each section alone (s, quiet 2-core machine, kernels compiled; the studies
#: with their sweeps in one process): only the order in which sections are handed to the workers
#: (longest first, so that none starts last on an idle pool) depends on these, never a result
SECTION_COST_S = {
    "study:fidelity": 255, "study:hard_cases": 210, "study:workprecision": 200, "study:convergence": 180,
    "study:deorbit": 170, "study:rigid_bodies": 56, "controls": 55, "study:bead_vs_tmed": 50,
    "study:stiefel_table": 34, "study:rigid_scenes": 33, "figures": 20, "check:invariants": 13,
    "check:vertical": 12, "check:libration": 7, "check:reproducible": 5, "study:catenary": 5,
}


def section_tasks(only=None, no_controls=False) -> list[str]:
    """Every section of a verify run, in the report's (canonical) order: the checks, the section
    4.3 figures, the studies (``only`` restricts them), the negative controls."""
    tasks = [f"check:{sid}" for sid, _t, _fn in CHECKS] + ["figures"]
    tasks += [f"study:{name}" for _t, name, *_ in STUDIES if only is None or name in only]
    return tasks + ([] if no_controls else ["controls"])


def run_task(task: str, out: str, study_workers: int | None = None) -> dict:
    """Run one section (in a worker process or in this one) and return what the report needs.

    Never raises: a section that fails returns its error beside everything it computed before
    the failure (the rows so far; a study's own files stay in its directory)."""
    out = Path(out)
    t0, c0 = time.perf_counter(), time.process_time()
    res = {"task": task, "rows": [], "values": {}, "error": None}
    try:
        if task.startswith("check:"):
            sid = task.split(":", 1)[1]
            fn = next(f for s, _t, f in CHECKS if s == sid)
            res["values"] = fn(res["rows"])
        elif task == "figures":
            res["figures"] = section_43_figures(out, res["rows"])
        elif task.startswith("study:"):
            name = task.split(":", 1)[1]
            sections, values, failures = run_studies(out, [name], study_workers=study_workers)
            res.update(studies=sections, values=values, failures=failures)
        elif task == "controls":
            gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
            cells, _baseline = run_negative_controls(res["rows"], gates)
            res["cells"] = cells
        else:
            raise ValueError(f"task: expected check:<id>, figures, study:<name> or controls, got {task!r}")
    except Exception as exc:  # report and go on: the other sections still run
        import traceback

        res["error"] = f"{type(exc).__name__}: {exc}"
        res["traceback"] = traceback.format_exc()[-2000:]
    res["wall_s"] = time.perf_counter() - t0
    res["cpu_s"] = time.process_time() - c0  # this process only: the studies' sweeps run in it (workers=1)
    res["pid"] = os.getpid()
    return res


def idle_machine_wall_s(results: dict, jobs: int) -> float:
    """The wall time the sections would take on ``jobs`` idle cores: their CPU times handed out
    longest-first (as run_tasks does) to the first free worker.  On a shared machine the measured
    wall time includes the other users' load; this estimate does not (it omits the start-up of the
    workers and a section's waiting on anything but its own CPU)."""
    free = [0.0] * max(1, jobs)
    for t in sorted(results, key=lambda t: -SECTION_COST_S.get(t, 1)):
        k = free.index(min(free))
        free[k] += results[t].get("cpu_s", math.nan)
    return max(free)


def run_tasks(tasks: list[str], out: Path, jobs: int, log=print) -> dict:
    """Run the sections on ``jobs`` worker processes (1: here, one after the other); return
    task -> result.  Sections start longest first (SECTION_COST_S); the results do not depend on
    which worker ran them or when (each section is deterministic and writes only its own files),
    and the caller assembles them in the canonical order.  A worker that dies takes the sections
    it was running with it: they are retried once in a fresh pool, then reported as lost."""
    results = {}
    order = sorted(tasks, key=lambda t: -SECTION_COST_S.get(t, 1))
    if jobs <= 1:
        for t in order:
            results[t] = run_task(t, str(out))
            log(f"[verify] {t}: {results[t]['wall_s']:.0f} s{' FAILED' if results[t]['error'] else ''}")
        return results
    import concurrent.futures as cf
    import multiprocessing

    pending = list(order)
    for attempt in (1, 2):
        if not pending:
            break
        # spawn: the workers load the numba kernels from the on-disk cache (no fork of this
        # process's threads); studies run their sweeps inside the worker (study_workers=1), so
        # at most ``jobs`` processes compute at any time
        pool = cf.ProcessPoolExecutor(max_workers=min(jobs, len(pending)), mp_context=multiprocessing.get_context("spawn"))
        futures = {pool.submit(run_task, t, str(out), 1): t for t in pending}
        lost = []
        try:
            for fut in cf.as_completed(futures):
                t = futures[fut]
                try:
                    results[t] = fut.result()
                    log(f"[verify] {t}: {results[t]['wall_s']:.0f} s (worker {results[t]['pid']})"
                        f"{' FAILED: ' + results[t]['error'] if results[t]['error'] else ''}", flush=True)
                except Exception as exc:  # noqa: BLE001 - a dead worker (BrokenProcessPool)
                    lost.append(t)
                    results[t] = {"task": t, "rows": [], "values": {}, "wall_s": math.nan,
                                  "error": f"worker lost (attempt {attempt}): {type(exc).__name__}: {exc}"}
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        pending = lost
    return results


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default=str(ROOT / "reports"))
    ap.add_argument("--only", nargs="*", help="run only these studies (names of studies/*.py)")
    ap.add_argument("--no-controls", action="store_true", help="skip the negative controls (mutation matrix)")
    ap.add_argument("--jobs", type=int, default=min(2, _cores()),
                    help="worker processes for the sections (default: 2, or 1 on a one-core machine)")
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error(f"--jobs: expected a positive integer, got {args.jobs}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
    t0 = time.perf_counter()
    tasks = section_tasks(args.only, args.no_controls)
    results = run_tasks(tasks, out, args.jobs, log=lambda *a, **k: print(*a, **{"flush": True, **k}))
    sections = {}  # id -> (title, rows, wall)
    values = {}
    section_failures = []
    for sid, title, _fn in CHECKS:
        r = results[f"check:{sid}"]
        rows = list(r["rows"])
        if r["error"]:
            rows.append({"case": f"SECTION FAILED: {r['error']}"})
            section_failures.append(f"section {sid} ({r['error']})")
        values.update(r["values"])
        sections[sid] = (title, rows, r["wall_s"])
    r = results["figures"]
    fig_rows, figs = list(r["rows"]), r.get("figures", [])
    if r["error"]:
        fig_rows.append({"case": f"SECTION FAILED: {r['error']}"})
        section_failures.append(f"figures ({r['error']})")
    study_sections, study_values, study_failures = [], {}, []
    for t in tasks:
        if t.startswith("study:"):
            r = results[t]
            if r["error"]:  # run_studies catches a study's own failure; this is a lost worker
                name = t.split(":", 1)[1]
                title = next(tt for tt, nm, *_ in STUDIES if nm == name)
                study_sections.append((name, title, f"**Study failed:** `{r['error']}`", r["wall_s"]))
                study_failures.append(name)
                continue
            study_sections += r["studies"]
            study_values.update(r["values"])
            study_failures += r["failures"]
    values.update(study_values)

    control_rows, cells, by_defect, by_gate = [], {}, {}, {}
    if not args.no_controls:
        r = results["controls"]
        control_rows, cells = list(r["rows"]), r.get("cells", {})
        if r["error"]:
            control_rows.append({"defect": f"SECTION FAILED: {r['error']}"})
            section_failures.append(f"negative controls ({r['error']})")
        by_defect, by_gate, mvals = mutation_summary(cells, gates, study_values)
        if not r["error"]:
            values.update(mvals)

    gate_rows = []
    failed = []
    partial = args.only is not None or args.no_controls
    for gid, g in gates.items():
        val = values.get(gid)
        ok = val is not None and val <= g["threshold"]
        skipped = val is None and partial  # a partial run (--only, --no-controls) does not fail them
        if not ok and not skipped:
            failed.append(gid)
        gate_rows.append({"gate": gid, "value": val if val is not None else "not measured",
                          "threshold": g["threshold"], "unit": g["unit"],
                          "result": "PASS" if ok else ("SKIPPED" if skipped else "FAIL")})  # fmt: skip
    failed += [f"study {name} (crashed)" for name in study_failures] + section_failures
    with open(out / "gates.csv", "w") as f:
        f.write("gate,value,threshold,unit,result\n")
        for r in gate_rows:
            f.write(f"{r['gate']},{r['value']},{r['threshold']},{r['unit']},{r['result']}\n")
    with open(out / "sections.csv", "w") as f:  # where the time went (order and workers vary; results do not)
        f.write("section,wall_s,cpu_s,worker_pid,result\n")
        for t in tasks:
            r = results[t]
            f.write(f"{t},{r['wall_s']:.1f},{r.get('cpu_s', math.nan):.1f},{r.get('pid', '')},"
                    f"{'FAILED' if r['error'] else 'ok'}\n")
    wall = time.perf_counter() - t0
    cpu = sum(r.get("cpu_s", math.nan) for r in results.values())
    print(f"sections: {cpu:.0f} s of CPU; on {args.jobs} idle core(s), longest first: about "
          f"{idle_machine_wall_s(results, args.jobs):.0f} s (measured wall {wall:.0f} s; OUT/sections.csv)", flush=True)

    from . import report
    from .provenance import footer, git_commit

    doc = report.Document(
        gates=gates, gate_rows=gate_rows, sections=sections, figures=figs, figure_rows=fig_rows,
        figure_section=FIGURE_SECTION, studies=study_sections, controls=(control_rows, cells, by_defect, by_gate),
        toothless=TOOTHLESS, retired=RETIRED, gate_section=gate_section, wall_s=wall, commit=git_commit(),
        footer=footer(), matrix_md=matrix_md(cells, gates, by_defect, by_gate) if cells else "",
    )  # fmt: skip
    md = doc.markdown()
    (out / "index.md").write_text(md)
    (out / "index.html").write_text(report.render_html(md, title="tetherlab verification report"))
    print(_table_md([{k: r[k] for k in ("gate", "value", "threshold", "unit", "result")} for r in gate_rows]))
    print(f"\nreport: {out / 'index.html'}  ({wall:.0f} s)")
    if failed:
        print(f"FAILED gates: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
