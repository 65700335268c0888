"""Part H of the deployment study: deployment from a spinning rigid hub with a wheel (docs/deployment.md 9).

A 200 kg hub (J = diag(40, 50, 60) kg m^2) spinning at 0.05 rad/s about its z axis (and 0.01 rad/s
about x), a wheel on its y axis free at 300 rpm, pays out 150 m of line (10 g/m, EA 2 kN, rods of
50 m) at 2 m/s for 120 s from a reel at (1, 0, 0.2) m in body axes, exit direction +x, the stored
2 km a ring of 0.3 m radius, to a 10 kg end mass co-rotating at 151 m.  Five births.  The exit
sits 0.2 m above the spin plane, so the flux and the line pull the spin axis off z: the hub cones.

Three reel laws run (constant with a canister, exponential with a drum, an out-and-back table with
a canister) and in each the total angular momentum of hub, wheel, stored tether, spool and rods
must stay within the integrator's error, 100 rtol |H(0)| (a quadratic invariant; docs/deployment.md
8), the linear momentum within 100 rtol sqrt(2 M K_max) (nonlinear in the state on a rigid hub: the
stored mass off the centre of mass moves with omega x m_s e), and E + W_exit (the exit's and the
reel's work, docs/deployment.md 9.3) constant to its quadrature's Richardson estimate, as part C.
On the spin axis the spool's inertia has a closed form: a hub spinning about its axis of largest
inertia pays the line out along that axis from a reel on it (exit and spool centred on the axis,
the ring about it), so the line, the end mass and the flux carry no angular momentum about the axis
and exert no torque about it; the hub with its stored turns keeps (J_zz + m_s R_s^2) omega_z, and
omega_z(t) = omega_0 (J_zz + m_s(0) R_s^2) / (J_zz + m_s(t) R_s^2): the hub spins up as the spool
empties (docs/deployment.md 9.2, the ring's term).  Bound: 100 rtol omega_0 (the integrator's
error); control: the ring's term dropped (DEFECT_REEL_NO_RING), omega_z then stays omega_0.

Controls: the constant-law run without the moment of the exit's momentum flux,
e x rho L'^2 (1 + eps) u (DEFECT_REEL_NO_EXIT_TORQUE), must fail the angular momentum bound;
without the centripetal term omega x (omega x e) of the exit point and the stored mass
(DEFECT_NO_CENTRIPETAL, the rigid bodies' defect), the momentum and the energy bounds.
"""

from __future__ import annotations

import math

import numpy as np

from tetherlab.deployment import simulate_reel
from tetherlab.model.params import DEFECT_NO_CENTRIPETAL, DEFECT_REEL_NO_EXIT_TORQUE, DEFECT_REEL_NO_RING
from tetherlab.scene import Scene

HUB_RTOL = 1e-11
SPIN_RAD_S = 0.05
HUB_KG, END_KG, RHO_KG_M, STORED_M = 200.0, 10.0, 0.01, 2000.0
EXIT_B = (1.0, 0.0, 0.2)  # m, body axes
J_ZZ, SPOOL_R = 60.0, 0.3  # kg m^2, m


def hub_scene(*, law="constant", exit_="canister", count=241, duration="120 s"):
    """The spinning hub of the module docstring with the law named (constant 2 m/s; exponential
    from 150 m at 2/150 1/s; a table out to 310 m and back to 290 m: births only)."""
    reel = {"law": law, "rod_length": "50 m", "stored_length": f"{STORED_M} m", "exit": exit_,
            "point": [f"{x} m" for x in EXIT_B], "exit_direction": [1, 0, 0], "spool_radius": f"{SPOOL_R} m"}  # fmt: skip
    if law == "constant":
        reel["speed"] = "2 m/s"
    elif law == "exponential":
        reel["rate"] = f"{2.0 / 150.0} 1/s"
    else:
        reel["times"] = ["0 s", "60 s", "120 s"]
        reel["lengths"] = ["150 m", "310 m", "290 m"]
    if exit_ == "drum":
        reel["spool_axis"] = [0, 0, 1]
    r_end = EXIT_B[0] + 150.0
    return Scene.from_dict({
        "name": f"hub-deploy-{law}-{exit_}", "duration": duration, "effects": {},
        "bodies": {
            "hub": {"mass": f"{HUB_KG} kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"],
                    "rigid": {"inertia": {"xx": "40 kg m2", "yy": "50 kg m2", "zz": f"{J_ZZ} kg m2"},
                              "attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]},
                              "angular_velocity": {"vector": ["0.01 rad/s", "0 rad/s", f"{SPIN_RAD_S} rad/s"],
                                                   "frame": "body"}},
                    "wheels": {"w1": {"axis": [0.0, 1.0, 0.0], "inertia": "0.1 kg m2", "speed": "300 rpm"}}},
            "mf": {"mass": f"{END_KG} kg", "position": [f"{r_end} m", "0 m", f"{EXIT_B[2]} m"],
                   "velocity": ["0 m/s", f"{r_end * SPIN_RAD_S} m/s", "0 m/s"]}},
        "tethers": {"main": {"from": "hub", "to": "mf", "length": "150 m", "EA": "2e3 N",
                             "linear_density": f"{RHO_KG_M} kg/m", "model": "energy", "reel": reel}},
        "integrator": {"method": "dop853", "rtol": HUB_RTOL, "atol": 1e-11},
        "output": {"count": count},
    })  # fmt: skip


def _vec(inv, kind):
    cols = [f"momentum_{a}_N_s" for a in "xyz"] if kind == "P" else [f"angmom_{a}_kg_m2_s" for a in "xyz"]
    return inv[cols].to_numpy()


def _energy_bound(coarse_run, fine_run):
    """Part C's bound: twice the Richardson estimate of the trapezoid error of W_exit (order 2)
    between the two output spacings, plus 1e-9 |W_exit|; and the coarse run's drift."""
    coarse, finer = (r.invariants.drop_duplicates("t_s").set_index("t_s")["exit_work_J"] for r in (coarse_run, fine_run))
    common = coarse.index.intersection(finer.index)
    est = float((coarse[common] - finer[common]).abs().max()) * 4.0 / 3.0
    w = float(coarse_run.invariants["exit_work_J"].iloc[-1])
    e = coarse_run.invariants["energy_plus_exit_work_J"].to_numpy()
    return float(np.abs(e - e[0]).max()), 2.0 * est + 1e-9 * abs(w), w


def hub_timeseries(run):
    """t, hub omega (body axes, 3 columns), deployed length, the whole run's rows."""
    import pandas as pd

    ts = pd.concat([ph.timeseries for ph in run.phases]).drop_duplicates("t_s")
    w = ts[[f"hub.omega_{a}_rad_s" for a in "xyz"]].to_numpy()
    L = run.reel.drop_duplicates("t_s")["deployed_length_m"].to_numpy()
    return ts["t_s"].to_numpy(), w, L


def rigid_spin_estimate(H_z, L):
    """The spin rate of the hub, stored tether, line and end mass turning together as one rigid
    body about z with the line straight and radial from the exit (rigid-rod estimate):
    H_z / I_z(L), I_z = J_zz + m_s (x_e^2 + R_s^2/2) + rho ((x_e + L)^3 - x_e^3)/3 + m_f (x_e + L)^2."""
    x = EXIT_B[0]
    ms = RHO_KG_M * (150.0 + STORED_M - L)
    i_z = J_ZZ + ms * (x * x + 0.5 * SPOOL_R**2) + RHO_KG_M * ((x + L) ** 3 - x**3) / 3.0 + END_KG * (x + L) ** 2
    return H_z / i_z


AXIS_SPIN_RAD_S, AXIS_STORED_M, AXIS_SPOOL_R, AXIS_SPEED = 0.5, 10000.0, 0.5, 5.0  # rad/s, m, m, m/s


def axis_scene(count=121):
    """The on-axis spin-up: the hub of hub_scene spinning at 0.5 rad/s about z pays out 10 km stored
    on a ring of 0.5 m (100 kg: m_s R_s^2 = 25 kg m^2 against J_zz = 60) at 5 m/s for 120 s along
    +z from (0, 0, 1) m, to a 10 kg end mass on the axis at rest."""
    reel = {"law": "constant", "speed": f"{AXIS_SPEED} m/s", "rod_length": "50 m", "stored_length": f"{AXIS_STORED_M} m",
            "point": ["0 m", "0 m", "1 m"], "exit_direction": [0, 0, 1], "spool_radius": f"{AXIS_SPOOL_R} m"}  # fmt: skip
    return Scene.from_dict({
        "name": "hub-axis-spin-up", "duration": "120 s", "effects": {},
        "bodies": {
            "hub": {"mass": f"{HUB_KG} kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"],
                    "rigid": {"inertia": {"xx": "40 kg m2", "yy": "50 kg m2", "zz": f"{J_ZZ} kg m2"},
                              "attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]},
                              "angular_velocity": {"vector": ["0 rad/s", "0 rad/s", f"{AXIS_SPIN_RAD_S} rad/s"],
                                                   "frame": "body"}}},
            "mf": {"mass": f"{END_KG} kg", "position": ["0 m", "0 m", "151 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]}},
        "tethers": {"main": {"from": "hub", "to": "mf", "length": "150 m", "EA": "2e3 N",
                             "linear_density": f"{RHO_KG_M} kg/m", "model": "energy", "reel": reel}},
        "integrator": {"method": "dop853", "rtol": HUB_RTOL, "atol": 1e-11},
        "output": {"count": count},
    })  # fmt: skip


def axis_spin_closed_form(t_s):
    """omega_z(t) = omega_0 (J_zz + m_s(0) R_s^2) / (J_zz + m_s(t) R_s^2), m_s = rho (stored - v t)."""
    ms = RHO_KG_M * (AXIS_STORED_M - AXIS_SPEED * np.asarray(t_s))
    ms0 = RHO_KG_M * AXIS_STORED_M
    r2 = AXIS_SPOOL_R**2
    return AXIS_SPIN_RAD_S * (J_ZZ + ms0 * r2) / (J_ZZ + ms * r2)


def axis_errors(run):
    """t, omega_z and its largest error against the closed form."""
    t, w, _ = hub_timeseries(run)
    return t, w[:, 2], float(np.abs(w[:, 2] - axis_spin_closed_form(t)).max())


def part_axis():
    run = simulate_reel(axis_scene())
    ctrl = simulate_reel(axis_scene(), defect=DEFECT_REEL_NO_RING, raise_on_failure=False)
    if not run.ok:
        raise RuntimeError(f"part H (on-axis): {run.message}")
    t, w, err = axis_errors(run)
    _, _, c_err = axis_errors(ctrl)
    bound = 100.0 * HUB_RTOL * AXIS_SPIN_RAD_S
    rise = float(axis_spin_closed_form(t[-1]) / AXIS_SPIN_RAD_S - 1.0)
    rows = [
        {"case": "G on-axis spin-up: |omega_z - closed form|", "value": err, "bound": bound, "over bound": err / bound,
         "unit": "rad/s", "note": f"{len(run.changes)} births; the closed form rises {rise:.3%} over the run"},
        {"case": "control: the ring's term dropped, on-axis spin-up", "value": c_err, "bound": bound,
         "over bound": c_err / bound, "unit": "rad/s", "note": "must exceed its bound"},
    ]  # fmt: skip
    gates = {"deployment_hub_axis_spin_over_bound": err / bound,
             "deployment_hub_ring_negative_control": bound / c_err if c_err > 0 else math.inf}
    return rows, gates, {"t": t, "w": w, "ctrl": axis_errors(ctrl)[:2]}


def part_hub():
    """G: the three laws, their bounds, the energy balance and the exit-torque control."""
    cases = (("constant", "canister"), ("exponential", "drum"), ("table", "canister"))
    runs = {c: simulate_reel(hub_scene(law=c[0], exit_=c[1])) for c in cases}
    fine = simulate_reel(hub_scene(count=481))
    ctrl = simulate_reel(hub_scene(), defect=DEFECT_REEL_NO_EXIT_TORQUE, raise_on_failure=False)
    cent = simulate_reel(hub_scene(), defect=DEFECT_NO_CENTRIPETAL, raise_on_failure=False)
    cent_fine = simulate_reel(hub_scene(count=481), defect=DEFECT_NO_CENTRIPETAL, raise_on_failure=False)
    rows, h_ratio, p_ratio = [], 0.0, 0.0
    mass = HUB_KG + END_KG + RHO_KG_M * (150.0 + STORED_M)
    for (law, exit_), run in runs.items():
        if not run.ok:
            raise RuntimeError(f"part H ({law}, {exit_}): {run.message}")
        H, P = _vec(run.invariants, "H"), _vec(run.invariants, "P")
        h0 = float(np.linalg.norm(H[0]))
        h_err, h_bound = float(np.abs(H - H[0]).max()), 100.0 * HUB_RTOL * h0
        p_scale = math.sqrt(2.0 * mass * float(run.invariants["kinetic_J"].max()))
        p_err, p_bound = float(np.abs(P - P[0]).max()), 100.0 * HUB_RTOL * p_scale
        kinds = [c["change"] for c in run.changes]
        rows.append({"case": f"G hub, {law} law, {exit_}: angular momentum |H(t) - H(0)|", "value": h_err, "bound": h_bound,
                     "over bound": h_err / h_bound, "unit": "kg m^2/s",
                     "note": f"|H(0)| = {h0:.5g} kg m^2/s; {len(kinds)} births"})  # fmt: skip
        rows.append({"case": f"G hub, {law} law, {exit_}: momentum |P(t) - P(0)|", "value": p_err, "bound": p_bound,
                     "over bound": p_err / p_bound, "unit": "N s", "note": f"sqrt(2 M K_max) = {p_scale:.4g} N s"})  # fmt: skip
        h_ratio = max(h_ratio, h_err / h_bound)
        p_ratio = max(p_ratio, p_err / p_bound)
    drift, e_bound, w = _energy_bound(runs[cases[0]], fine)
    rows.append({"case": "G hub, constant law, canister: energy |E + W_exit - const| (241 outputs)", "value": drift,
                 "bound": e_bound, "over bound": drift / e_bound, "unit": "J",
                 "note": f"W_exit = {w:.4g} J (exit, ring and drum work, docs/deployment.md 9.3)"})  # fmt: skip
    Hc = _vec(ctrl.invariants, "H")
    H0 = _vec(runs[cases[0]].invariants, "H")
    hc_bound = 100.0 * HUB_RTOL * float(np.linalg.norm(H0[0]))
    hc_err = float(np.abs(Hc - Hc[0]).max()) if Hc.shape[0] > 1 else math.inf
    ec_drift = _energy_bound(cent, cent_fine)[0] if cent.invariants.shape[0] > 1 else math.inf
    # the centripetal term omega x (omega x e) dropped (the attachment's and the stored mass's): momentum
    Pc = _vec(cent.invariants, "P")
    p_bound0 = 100.0 * HUB_RTOL * math.sqrt(2.0 * mass * float(runs[cases[0]].invariants["kinetic_J"].max()))
    pc_err = float(np.abs(Pc - Pc[0]).max()) if Pc.shape[0] > 1 else math.inf
    rows += [
        {"case": "control: exit torque dropped, angular momentum", "value": hc_err, "bound": hc_bound,
         "over bound": hc_err / hc_bound, "unit": "kg m^2/s", "note": "must exceed its bound"},
        {"case": "control: centripetal term dropped, momentum", "value": pc_err, "bound": p_bound0,
         "over bound": pc_err / p_bound0, "unit": "N s", "note": "must exceed its bound"
         + ("" if cent.ok else f" (stopped: {cent.message[:50]})")},
        {"case": "control: centripetal term dropped, energy", "value": ec_drift, "bound": e_bound,
         "over bound": ec_drift / e_bound, "unit": "J", "note": "must exceed the nominal run's bound"},
    ]  # fmt: skip
    weakest = min(pc_err / p_bound0, ec_drift / e_bound)
    gates = {
        "deployment_hub_angular_momentum_over_bound": h_ratio,
        "deployment_hub_momentum_over_bound": p_ratio,
        "deployment_hub_energy_over_bound": drift / e_bound,
        "deployment_hub_exit_torque_negative_control": hc_bound / hc_err if hc_err > 0 else math.inf,
        # bound / measured of the control's weakest failure: below 1 when it failed every gate it must
        "deployment_hub_centripetal_negative_control": 1.0 / weakest if weakest > 0 else math.inf,
    }
    a_rows, a_gates, axis = part_axis()
    rows += a_rows
    gates.update(a_gates)
    return rows, gates, {"runs": runs, "ctrl": ctrl, "h_bound": hc_bound, "axis": axis}


def hub_figure(out, hub, plt) -> list[str]:
    """The attitude of the hub as it pays out (spin rate against the rigid-rod estimate, the coning
    rates), and the angular momentum error of each law and of the control against the bound."""
    if hub is None:
        return []
    fig, axes = plt.subplots(1, 4, figsize=(24, 4.4))
    for k, ((law, exit_), run) in enumerate(hub["runs"].items()):
        t, w, L = hub_timeseries(run)
        H = _vec(run.invariants.drop_duplicates("t_s"), "H")
        axes[0].plot(t, w[:, 2], f"C{k}-", label=f"omega_z, {law} ({exit_})")
        if k == 0:
            axes[0].plot(t, rigid_spin_estimate(H[:, 2], L), "k--", lw=1, label="rigid-rod estimate H_z / I_z(L)")
            axes[1].plot(t, w[:, 0], "C0-", label="omega_x")
            axes[1].plot(t, w[:, 1], "C1-", label="omega_y")
        err = np.linalg.norm(H - H[0], axis=1)
        axes[2].semilogy(t, np.maximum(err, 1e-16), f"C{k}-", label=f"{law} ({exit_})")
    Hc = _vec(hub["ctrl"].invariants.drop_duplicates("t_s"), "H")
    tc = hub["ctrl"].invariants.drop_duplicates("t_s")["t_s"].to_numpy()
    axes[2].semilogy(tc, np.maximum(np.linalg.norm(Hc - Hc[0], axis=1), 1e-16), "C3:", label="control: exit torque dropped")
    axes[2].axhline(hub["h_bound"], color="C3", ls="--", label=f"bound 100 rtol |H(0)| = {hub['h_bound']:.2g}")
    axes[0].set_title("G: hub spin rate as the line pays out")
    axes[0].set_ylabel("rad/s (body axes)")
    axes[1].set_title("G: coning (constant law): the exit 0.2 m off the spin plane")
    axes[1].set_ylabel("rad/s (body axes)")
    axes[2].set_title("G: total angular momentum error")
    axes[2].set_ylabel("|H(t) - H(0)| (kg m^2/s)")
    ax = axes[3]
    axis = hub["axis"]
    ax.plot(axis["t"], axis["w"], "C0-", label="omega_z, the model")
    ax.plot(axis["t"], axis_spin_closed_form(axis["t"]), "k--", lw=1,
            label="closed form omega_0 (J + m_s(0) R_s^2) / (J + m_s(t) R_s^2)")
    ax.plot(axis["ctrl"][0], axis["ctrl"][1], "C3:", label="control: the ring's term dropped")
    ax.set_title("G: on-axis spin-up as the spool empties")
    ax.set_ylabel("rad/s")
    for ax in axes:
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    name = "deployment_hub_attitude.png"
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    return [name]


# -- part R: a drum under a spool law on the hub (docs/deployment.md 9.7) -----------------------
DRUM_J, DRUM_TORQUES = 0.5, (("brake", "0.01 N m"), ("motor", "-0.3 N m"))  # kg m^2 on SPOOL_R; N m


def drum_scene(torque, *, duration="60 s", count=121):
    """The hub of hub_scene paying out from a drum of J = 0.5 kg m^2 on R = 0.3 m (axis z, the turns'
    ring on the rim) under the spool law from 2 m/s, against a constant torque (0.01 N m: a brake;
    -0.3 N m: a motor paying out) and a viscous friction of 0.5 N s/m."""
    data = hub_scene(duration=duration, count=count).to_dict()
    data["tethers"]["main"]["reel"].update({
        "law": "spool", "exit": "drum", "speed": "2 m/s", "drum_radius": f"{SPOOL_R} m", "spool_axis": [0, 0, 1],
        "spool_inertia": f"{DRUM_J} kg m2", "torque": torque, "viscous_friction": "0.5 N s/m"})  # fmt: skip
    return Scene.from_dict(data)


def drum_ratios(run):
    """(|H - H(0)| max / (100 rtol |H(0)|), (10.3)'s drift / (2 Richardson est + 100 rtol max |E|)),
    the bounds of part H and of the spool's energy gate (studies/reel_laws.py spool_energy)."""
    from studies.reel_laws import spool_energy

    H = _vec(run.invariants, "H")
    h = float(np.abs(H - H[0]).max()) / (100.0 * HUB_RTOL * float(np.linalg.norm(H[0])))
    total, est = spool_energy(run)
    scale = float(np.abs(run.invariants["energy_J"]).max())
    e = float(np.abs(total - total[0]).max()) / (2.0 * est + 100.0 * HUB_RTOL * scale)
    return h, e


def part_hub_drum():
    """R: the drum under a brake and under a motor: H (the drum's own spin included) and (10.3)
    within their bounds; control: the old model (DEFECT_HUB_DRUM_NO_SPIN) on the brake run."""
    from tetherlab import mutants

    rows, h_worst, e_worst = [], 0.0, 0.0
    for label, torque in DRUM_TORQUES:
        run = simulate_reel(drum_scene(torque), progress=False)
        if not run.ok:
            raise RuntimeError(f"part R ({label}): {run.message}")
        h, e = drum_ratios(run)
        h_worst, e_worst = max(h_worst, h), max(e_worst, e)
        r = run.reel
        rows.append({"case": f"R drum on the hub, {label} {torque}: |H - H(0)| / bound, (10.3) drift / bound",
                     "value": h, "unit": "1", "note": f"energy {e:.3g}; L' 2 -> {float(r['speed_m_s'].iloc[-1]):.3g} m/s, "
                     f"brake work {float(r['brake_work_J'].iloc[-1]):.4g} J, {len(run.changes)} births"})  # fmt: skip
    with mutants.active("hub_drum_no_spin"):
        ctrl = simulate_reel(drum_scene(DRUM_TORQUES[0][1]), progress=False)
    # the control's weakest failure over the two gates (bound / measured: below 1 when it failed both)
    control = max(1.0 / r for r in drum_ratios(ctrl)) if ctrl.ok else math.inf
    rows.append({"case": "R control: the old model (the drum's spin out of both balances), bound / measured",
                 "value": control, "unit": "1"})
    gates = {"deployment_hub_drum_angular_momentum_over_bound": h_worst,
             "deployment_hub_drum_energy_over_bound": e_worst,
             "deployment_hub_drum_negative_control": control}
    return rows, gates, None
