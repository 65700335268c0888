"""Parts P and Q of the deployment study: a spinning hub deploying tethers hub-and-spoke under a spool law.

A 500 kg hub (J = diag(400, 400, 600) kg m^2) spinning at 1 rpm about its z axis pays out two or
four tethers symmetrically in its spin plane (exits at 0.5 m from the centre of mass, radial exit
directions, 0.1 m above the spin plane, canister reels: the line is pulled off a spool at rest in the hub and held by a
viscous brake, law `spool`), each to a 5 kg end mass, from 20 m (rods of 10 m, 5 g/m, EA 5 kN,
500 m stored on a ring of 0.3 m).  docs/deployment.md 9.5 derives the rigid-body estimate of the
spin rate from the angular momentum about z and the inertia I_z(L) of the hub, the stored rings
and the straight radial lines, and when it holds.

P: the symmetric deployment, with the wheels free (no control) and with a PD attitude controller
through three wheels holding the initial attitude (inertial), so that the hub's angular momentum
goes into the wheels.  Q: one tether's brake stronger (asymmetric deployment): the hub's centre of
mass and its spin axis move (nutation) and the controller's answer.
"""

from __future__ import annotations

import math

import numpy as np

from tetherlab.scene import Scene

SPOKE_RTOL = 1e-10
HUB_KG, J_XX, J_ZZ = 500.0, 400.0, 600.0  # kg, kg m^2
SPIN_RAD_S = 2.0 * math.pi / 60.0  # 1 rpm
EXIT_R, END_KG, RHO_KG_M, STORED_M, L0_M, SPOOL_R = 0.5, 5.0, 0.005, 500.0, 20.0, 0.3
EA_N = 5e3
BRAKE_N_S_M = 0.5  # N s/m, the viscous brake of each spool
EXIT_Z = 0.1  # m: the radial spokes' exits sit this far above the hub's spin plane


def spoke_scene(*, n_tethers=4, duration="300 s", count=301, control=False, lag=1.0, wheel_speed_rpm=0.0,
                wheel_torque=None):
    """The hub of the module docstring with n_tethers (2 or 4) spokes; ``lag`` multiplies the first
    spool's brake (1: symmetric); ``control``: three wheels under a PD law holding the initial
    attitude; else one free wheel on z at ``wheel_speed_rpm`` with the constant ``wheel_torque``."""
    w = SPIN_RAD_S
    bodies = {"hub": {"mass": f"{HUB_KG} kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"],
                      "rigid": {"inertia": {"xx": f"{J_XX} kg m2", "yy": f"{J_XX} kg m2", "zz": f"{J_ZZ} kg m2"},
                                "attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]},
                                "angular_velocity": {"vector": ["0 rad/s", "0 rad/s", f"{w} rad/s"], "frame": "body"}}}}  # fmt: skip
    hub = bodies["hub"]
    if control:
        hub["wheels"] = {f"w{i}": {"axis": [float(v) for v in np.eye(3)[i]], "inertia": "0.5 kg m2", "speed": "0 rpm",
                                   "torque": "control"} for i in range(3)}  # fmt: skip
        hub["control"] = {"law": "pd", "target": {"quaternion": [1.0, 0.0, 0.0, 0.0]}, "kp": "2 N m", "kd": "40 N m s"}
    else:
        wheel = {"axis": [0.0, 0.0, 1.0], "inertia": "0.5 kg m2", "speed": f"{wheel_speed_rpm} rpm"}
        if wheel_torque is not None:
            wheel["torque"] = wheel_torque
        hub["wheels"] = {"wz": wheel}
    tethers = {}
    for k in range(n_tethers):
        ang = 2.0 * math.pi * k / n_tethers
        u = (math.cos(ang), math.sin(ang), 0.0)
        r_end = EXIT_R + L0_M
        name = f"m{k}"
        bodies[name] = {"mass": f"{END_KG} kg", "position": [f"{r_end * u[0]} m", f"{r_end * u[1]} m", f"{EXIT_Z} m"],
                        "velocity": [f"{-w * r_end * u[1]} m/s", f"{w * r_end * u[0]} m/s", "0 m/s"]}  # fmt: skip
        reel = {"law": "spool", "speed": "0.5 m/s", "rod_length": "10 m", "stored_length": f"{STORED_M} m",
                "exit": "canister", "point": [f"{EXIT_R * u[0]} m", f"{EXIT_R * u[1]} m", f"{EXIT_Z} m"], "exit_direction": list(u),
                "spool_radius": f"{SPOOL_R} m", "viscous_friction": f"{BRAKE_N_S_M * (lag if k == 0 else 1.0)} N s/m"}  # fmt: skip
        tethers[f"t{k}"] = {"from": "hub", "from_point": reel["point"], "to": name, "length": f"{L0_M} m", "EA": f"{EA_N} N",
                            "linear_density": f"{RHO_KG_M} kg/m", "model": "energy", "reel": reel}
    return Scene.from_dict({
        "name": f"hub-spoke-{n_tethers}" + ("-pd" if control else "") + ("" if lag == 1.0 else "-lag"),
        "duration": duration, "effects": {}, "bodies": bodies, "tethers": tethers,
        "integrator": {"method": "dop853", "rtol": SPOKE_RTOL, "atol": 1e-10},
        "output": {"count": count},
    })  # fmt: skip


AXIS_RHO_KG_M, AXIS_STORED_M, AXIS_SPOOL_R = 0.05, 2000.0, 0.5  # kg/m, m, m


def axis_spoke_scene(*, duration="120 s", count=121):
    """Two spokes along the spin axis: the hub of spoke_scene pays out two 50 g/m tethers along +z
    and -z from exits at (0, 0, +-0.5) m (canister rings of 0.5 m about z, 2 km stored each: 100 kg,
    m_s R_s^2 = 25 kg m^2 against J_zz = 600), rods of 25 m, under the spool law from 2 m/s against
    viscous brakes of 0.05 and 0.1 N s/m (different, so the two lengths differ), to 5 kg end
    masses on the axis moving out at 2 m/s; no wheels."""
    w = SPIN_RAD_S
    bodies = {"hub": {"mass": f"{HUB_KG} kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"],
                      "rigid": {"inertia": {"xx": f"{J_XX} kg m2", "yy": f"{J_XX} kg m2", "zz": f"{J_ZZ} kg m2"},
                                "attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]},
                                "angular_velocity": {"vector": ["0 rad/s", "0 rad/s", f"{w} rad/s"], "frame": "body"}}}}  # fmt: skip
    tethers = {}
    for k, (sgn, brake) in enumerate(((1.0, 0.05), (-1.0, 0.1))):
        bodies[f"a{k}"] = {"mass": f"{END_KG} kg", "position": ["0 m", "0 m", f"{sgn * (EXIT_R + L0_M)} m"],
                           "velocity": ["0 m/s", "0 m/s", f"{sgn * 2.0} m/s"]}  # fmt: skip
        reel = {"law": "spool", "speed": "2 m/s", "rod_length": "25 m", "stored_length": f"{AXIS_STORED_M} m",
                "exit": "canister", "point": ["0 m", "0 m", f"{sgn * EXIT_R} m"], "exit_direction": [0, 0, sgn],
                "spool_radius": f"{AXIS_SPOOL_R} m", "viscous_friction": f"{brake} N s/m"}  # fmt: skip
        tethers[f"z{k}"] = {"from": "hub", "from_point": reel["point"], "to": f"a{k}", "length": f"{L0_M} m",
                            "EA": f"{EA_N} N", "linear_density": f"{AXIS_RHO_KG_M} kg/m", "model": "energy", "reel": reel}  # fmt: skip
    return Scene.from_dict({
        "name": "hub-spoke-axis", "duration": duration, "effects": {}, "bodies": bodies, "tethers": tethers,
        "integrator": {"method": "dop853", "rtol": SPOKE_RTOL, "atol": 1e-10}, "output": {"count": count},
    })  # fmt: skip


def run_frames(run):
    """(timeseries, reel table per reel (dict), invariants), each without the duplicate rows at the
    phases' joints."""
    import pandas as pd

    ts = pd.concat([ph.timeseries for ph in run.phases]).drop_duplicates("t_s").reset_index(drop=True)
    reels = {name: g.drop_duplicates("t_s").reset_index(drop=True) for name, g in run.reel.groupby("reel")}
    inv = run.invariants.drop_duplicates("t_s").reset_index(drop=True)
    return ts, reels, inv


def axis_spin_closed_form(reels, omega0=SPIN_RAD_S):
    """omega_z = omega_0 (J_zz + sum m_s,k(0) R_s^2) / (J_zz + sum m_s,k(t) R_s^2), the stored masses
    from the run's own deployed lengths (docs/deployment.md 9.5)."""
    stored = sum(AXIS_RHO_KG_M * (AXIS_STORED_M + L0_M - r["deployed_length_m"].to_numpy()) for r in reels.values())
    stored0 = len(reels) * AXIS_RHO_KG_M * AXIS_STORED_M
    r2 = AXIS_SPOOL_R**2
    return omega0 * (J_ZZ + stored0 * r2) / (J_ZZ + stored * r2)


def axis_errors(run):
    """t, omega_z, the closed form and the largest error."""
    ts, reels, _ = run_frames(run)
    w = ts["hub.omega_z_rad_s"].to_numpy()
    cf = axis_spin_closed_form(reels)
    return ts["t_s"].to_numpy(), w, cf, float(np.abs(w - cf).max())


def rigid_spin_estimate(inv, reels, n_tethers):
    """H_z / I_z(L): the hub, its rings, the straight radial lines and the end masses turning as one
    (docs/deployment.md 9.5), I_z = J_zz + sum_k [m_s,k (x_e^2 + R_s^2/2) + rho ((x_e + L_k)^3 - x_e^3)/3
    + m_f (x_e + L_k)^2]."""
    x = EXIT_R
    i_z = J_ZZ
    for r in reels.values():
        L = r["deployed_length_m"].to_numpy()
        ms = RHO_KG_M * (STORED_M + L0_M - L)
        i_z = i_z + ms * (x * x + 0.5 * SPOOL_R**2) + RHO_KG_M * ((x + L) ** 3 - x**3) / 3.0 + END_KG * (x + L) ** 2
    return inv["angmom_z_kg_m2_s"].to_numpy() / i_z


def _vec(inv, kind):
    cols = [f"momentum_{a}_N_s" for a in "xyz"] if kind == "P" else [f"angmom_{a}_kg_m2_s" for a in "xyz"]
    return inv[cols].to_numpy()


def _momentum_error(run):
    """(max_t |P(t) - P(0)|, 100 rtol sqrt(2 M K_max)): the momentum's drift and its bound (part H's,
    M the whole system's mass)."""
    P = _vec(run.invariants, "P")
    n = len(run.reel["reel"].unique())
    mass = HUB_KG + n * (END_KG + RHO_KG_M * (STORED_M + L0_M))
    scale = math.sqrt(2.0 * mass * float(run.invariants["kinetic_J"].max()))
    return float(np.abs(P - P[0]).max()), 100.0 * SPOKE_RTOL * scale


def estimate_rows(run):
    """Measured, not gated (docs/deployment.md 9.5): the end masses' rate about z and the hub's
    against the rigid-body estimate H_z / I_z(L) of the symmetric radial spokes."""
    ts, reels, inv = run_frames(run)
    est = rigid_spin_estimate(inv, reels, len(reels))
    tip = []
    for k in range(len(reels)):
        x, y, vx, vy = (ts[f"m{k}.{c}"].to_numpy() for c in ("x_m", "y_m", "vx_m_s", "vy_m_s"))
        tip.append((x * vy - y * vx) / (x * x + y * y))
    tip_dev = float(np.abs(np.array(tip) / est - 1.0).max())
    hub = ts["hub.omega_z_rad_s"].to_numpy()
    return [
        {"case": "P four radial spokes, free wheel: end masses' rate about z against H_z / I_z(L)", "value": tip_dev,
         "unit": "1 (relative)", "note": f"measured, not gated; the estimate falls from {est[0]:.4g} to {est[-1]:.4g} rad/s"},
        {"case": "P four radial spokes, free wheel: the hub's omega_z at the end against H_z / I_z(L)",
         "value": float(hub[-1] / est[-1]), "unit": "ratio",
         "note": f"hub {hub[-1]:.4g} rad/s (range {hub.min():.4g}-{hub.max():.4g}): held only by the exits' moments"},
    ]  # fmt: skip


def part_spokes():
    """P: the gates (the spin-up along the axis against its closed form; the angular momentum of the
    radial spokes with the PD controller's wheels) with their controls, and the runs of the figure."""
    from tetherlab.deployment import simulate_reel
    from tetherlab.model.params import DEFECT_REEL_ONE_STORED, DEFECT_REEL_RING_FULL, DEFECT_WHEELS_NO_GYRO

    axis = simulate_reel(axis_spoke_scene(), progress=False)
    if not axis.ok:
        raise RuntimeError(f"part P (axis): {axis.message}")
    axis_c = simulate_reel(axis_spoke_scene(), defect=DEFECT_REEL_RING_FULL, raise_on_failure=False, progress=False)
    t, w, cf, err = axis_errors(axis)
    c_err = axis_errors(axis_c)[3] if len(axis_c.phases) else math.inf
    bound = 100.0 * SPOKE_RTOL * SPIN_RAD_S
    rise = float(cf[-1] / SPIN_RAD_S - 1.0)
    pd = simulate_reel(spoke_scene(control=True), progress=False)
    if not pd.ok:
        raise RuntimeError(f"part P (PD): {pd.message}")
    # the wheels' control runs on the lagging spoke: with the four spokes alike the hub turns about z
    # only, the wheels' momentum lies along z too, and omega x h_w (the term the defect drops) is zero
    pd_lag = simulate_reel(spoke_scene(lag=3.0, control=True), progress=False)
    pd_c = simulate_reel(spoke_scene(lag=3.0, control=True), defect=DEFECT_WHEELS_NO_GYRO, raise_on_failure=False,
                         progress=False)  # fmt: skip
    free = simulate_reel(spoke_scene(), progress=False)
    lag = simulate_reel(spoke_scene(lag=3.0), progress=False)
    lag_c = simulate_reel(spoke_scene(lag=3.0), defect=DEFECT_REEL_ONE_STORED, raise_on_failure=False, progress=False)
    rows = [
        {"case": "P two spokes on the spin axis: |omega_z - closed form|", "value": err, "bound": bound,
         "over bound": err / bound, "unit": "rad/s",
         "note": f"{len(axis.changes)} births; the closed form rises {rise:.3%}"},
        {"case": "control: the ring's inertia kept full, spin-up on the axis", "value": c_err, "bound": bound,
         "over bound": c_err / bound, "unit": "rad/s", "note": "must exceed its bound"},
    ]  # fmt: skip
    gates = {"deployment_spoke_axis_spin_over_bound": err / bound,
             "deployment_spoke_ring_full_negative_control": bound / c_err if c_err > 0 else math.inf}
    h_worst, p_worst = 0.0, 0.0
    for label, run in (("PD-held hub, 3 wheels", pd), ("free wheel", free), ("one spoke lagging, free wheel", lag),
                       ("one spoke lagging, PD-held hub, 3 wheels", pd_lag)):  # fmt: skip
        if not run.ok:
            raise RuntimeError(f"part P ({label}): {run.message}")
        H = _vec(run.invariants, "H")
        h_err, h_bound = float(np.abs(H - H[0]).max()), 100.0 * SPOKE_RTOL * float(np.linalg.norm(H[0]))
        h_worst = max(h_worst, h_err / h_bound)
        p_err, p_bound = _momentum_error(run)
        p_worst = max(p_worst, p_err / p_bound)
        rows.append({"case": f"P four radial spokes, {label}: angular momentum |H(t) - H(0)|", "value": h_err,
                     "bound": h_bound, "over bound": h_err / h_bound, "unit": "kg m^2/s",
                     "note": f"{len(run.changes)} births; |H(0)| = {np.linalg.norm(H[0]):.5g} kg m^2/s (wheels included)"})  # fmt: skip
        rows.append({"case": f"P four radial spokes, {label}: momentum |P(t) - P(0)|", "value": p_err,
                     "bound": p_bound, "over bound": p_err / p_bound, "unit": "N s", "note": "bound 100 rtol sqrt(2 M K_max)"})  # fmt: skip
    rows += estimate_rows(free)
    pc_err = _momentum_error(lag_c)[0] if lag_c.invariants.shape[0] > 1 else math.inf
    pc_bound = _momentum_error(lag)[1]
    rows.append({"case": "control: the hub's mass with one reel's stored line only, one spoke lagging", "value": pc_err,
                 "bound": pc_bound, "over bound": pc_err / pc_bound, "unit": "N s", "note": "must exceed its bound"})  # fmt: skip
    gates["deployment_spoke_momentum_over_bound"] = p_worst
    gates["deployment_spoke_one_stored_negative_control"] = pc_bound / pc_err if pc_err > 0 else math.inf
    Hc = _vec(pd_c.invariants, "H") if pd_c.invariants.shape[0] > 1 else None
    H0 = _vec(pd_lag.invariants, "H")
    hc_bound = 100.0 * SPOKE_RTOL * float(np.linalg.norm(H0[0]))
    hc_err = float(np.abs(Hc - Hc[0]).max()) if Hc is not None else math.inf
    rows.append({"case": "control: the wheels' momentum left out of the gyroscopic torque, PD-held hub, one spoke lagging", "value": hc_err,
                 "bound": hc_bound, "over bound": hc_err / hc_bound, "unit": "kg m^2/s", "note": "must exceed its bound"})  # fmt: skip
    gates["deployment_spoke_angular_momentum_over_bound"] = h_worst
    gates["deployment_spoke_wheels_negative_control"] = hc_bound / hc_err if hc_err > 0 else math.inf
    return rows, gates, {"axis": (t, w, cf), "axis_ctrl": axis_errors(axis_c)[:3] if len(axis_c.phases) else None,
                         "pd": pd, "free": free, "lag": lag, "pd_ctrl": pd_c, "h_bound": hc_bound}  # fmt: skip


def part_lag():
    """Q: the first spool's brake three times the others' (asymmetric deployment), wheel free and
    with the PD controller: measured, not gated (docs/deployment.md 9.5)."""
    from tetherlab.deployment import simulate_reel

    lag = simulate_reel(spoke_scene(lag=3.0), progress=False)  # (P runs it too; a part runs alone)
    lag_pd = simulate_reel(spoke_scene(lag=3.0, control=True), progress=False)
    rows = []
    for label, run in (("wheel free", lag), ("PD-held", lag_pd)):
        if not run.ok:
            raise RuntimeError(f"part Q ({label}): {run.message}")
        ts, reels, inv = run_frames(run)
        wxy = np.hypot(ts["hub.omega_x_rad_s"], ts["hub.omega_y_rad_s"]).to_numpy()
        off = np.hypot(ts["hub.x_m"], ts["hub.y_m"]).to_numpy()
        H = _vec(run.invariants, "H")
        h_err = float(np.abs(H - H[0]).max())
        spread = max(float(r["deployed_length_m"].iloc[-1]) for r in reels.values()) - min(
            float(r["deployed_length_m"].iloc[-1]) for r in reels.values())
        rows.append({"case": f"Q one spoke lagging, {label}: largest transverse rate |omega_xy|", "value": float(wxy.max()),
                     "unit": "rad/s", "note": f"lengths spread {spread:.3g} m at the end; hub off the origin up to "
                     f"{off.max():.3g} m; |H - H(0)| {h_err:.2g} kg m^2/s"})  # fmt: skip
    return rows, {}, {"lag": lag, "lag_pd": lag_pd}


def spoke_figure(out, spokes, lag, plt) -> list[str]:
    """P and Q: the spin-up on the axis against its closed form; the radial spokes' hub spin and
    end-mass rate against the rigid-body estimate, free and PD-held, with the wheels' momentum; the
    lagging spoke's nutation and the hub's drift."""
    if spokes is None:
        return []
    fig, axes = plt.subplots(1, 4, figsize=(24, 4.4))
    t, w, cf = spokes["axis"]
    ax = axes[0]
    ax.plot(t, w, "C0-", label="omega_z, the model")
    ax.plot(t, cf, "k--", lw=1, label="closed form (J + sum m_s(0) R^2) / (J + sum m_s(t) R^2)")
    if spokes["axis_ctrl"] is not None:
        ax.plot(spokes["axis_ctrl"][0], spokes["axis_ctrl"][1], "C3:", label="control: the ring's inertia kept full")
    ax.set_title("P: two spokes on the spin axis")
    ax.set_ylabel("rad/s")
    ax = axes[1]
    for k, (label, run) in enumerate((("wheel free", spokes["free"]), ("PD-held", spokes["pd"]))):
        ts, reels, inv = run_frames(run)
        tt = ts["t_s"].to_numpy()
        ax.plot(tt, ts["hub.omega_z_rad_s"], f"C{k}-", label=f"hub omega_z, {label}")
        x, y, vx, vy = (ts[f"m1.{c}"].to_numpy() for c in ("x_m", "y_m", "vx_m_s", "vy_m_s"))
        ax.plot(tt, (x * vy - y * vx) / (x * x + y * y), f"C{k}:", label=f"end mass's rate about z, {label}")
        if k == 0:
            ax.plot(tt, rigid_spin_estimate(inv, reels, 4), "k--", lw=1, label="rigid-body estimate H_z / I_z(L)")
        if k == 1:
            hw = sum(ts[c].to_numpy() for c in ts.columns if c.startswith("hub.w") and c.endswith("momentum_N_m_s"))
            axes[2].plot(tt, hw, "C1-", label="wheels' momentum (body axes, summed)")
            axes[2].plot(tt, J_ZZ * ts["hub.omega_z_rad_s"].to_numpy(), "C0-", label="J_zz omega_z of the hub")
    ax.set_title("P: four radial spokes, spin rates")
    ax.set_ylabel("rad/s")
    axes[2].set_title("P: PD-held hub: where the hub's spin goes")
    axes[2].set_ylabel("kg m^2/s")
    ax = axes[3]
    if lag is not None:
        for k, (label, run) in enumerate((("wheel free", lag["lag"]), ("PD-held", lag["lag_pd"]))):
            ts, _, _ = run_frames(run)
            ax.plot(ts["t_s"], np.maximum(np.hypot(ts["hub.omega_x_rad_s"], ts["hub.omega_y_rad_s"]), 1e-16), f"C{k}-",
                    label=f"|omega_xy| of the hub, {label}")
        ax.set_yscale("log")
    ax.set_title("Q: one spoke lagging (its brake 3x): nutation")
    ax.set_ylabel("rad/s")
    for ax in axes:
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    name = "deployment_spoke_attitude.png"
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    return [name]
