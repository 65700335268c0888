"""The spool laws' smooth limits on the motor's torque and on the pay-out speed (docs/deployment.md
10.4): a run that hits both, and its three bounds.

The scene is the drum of docs/deployment.md 11.1 (a fixed nail pays a 1 kg/m line out to a 10 kg
end mass hanging in uniform gravity, J/R^2 = 50 kg, R = 0.2 m, 10 m out and 90 m stored) under the
tension law used as a motor command in uniform gravity: T_c = m* Omega^2 [3 l_c + k1 (L - l_c) +
k2 L'/Omega] with m* Omega^2 = 5 N/m, l_c = 10 m, k1 = 4, k2 = 1 (150 N at the start, against the
196 N weight of the end mass and the line, so the line pays out and the command grows at 20 N/m),
the motor's torque limited to 32 N m (160 N at the rim, reached at L ~ 10.5 m), so the weight
(9.8 N per metre paid out) wins and the drum accelerates until the regulating brake (1.5 m/s,
1000 N s/m) holds it.

The bounds, each from the balance m_s L'' = T - j - F_b (docs/deployment.md 10.1, 10.4):

* torque: |tau| <= tau_max + w_tau e^(-2 tau_max/w_tau) (the corners' algebra; the budget takes
  w_tau ln 2, an upper bound of that);
* speed: at the largest L' of the run, either an interior maximum (L'' = 0) or the end with
  L'' >= 0, so F_v <= T - j - tau/R - F_f there, and F_v >= gain (|L'| - v_max) - gain w_v ln 2, so
  max |L'| <= v_max + max_t (T - j - tau/R - F_f)^+ / gain + w_v ln 2, plus the integrator's
  10 rtol v_max;
* energy (10.3): E + K_s + W_b + W_loss = const, W_b holding the limited torque's and the regulating
  brake's work; the budget is that of docs/deployment.md 11.2 (twice the Richardson estimate of the
  works' trapezoid rule on the outputs plus 100 rtol of the energies that move).

and one exact check: the balance the outputs report closes, m_s L'' = T - j - tau/R - F_f - F_v
with the applied (limited) torque and the brake's force, to the round-off of the L'' solve
(1e3 eps_mach of the largest of its terms).

Negative controls (tether/reel_spool.py): DEFECT_SPOOL_TORQUE_UNLIMITED puts the motor's unlimited
command into the balance while the outputs report the limited torque: the balance's residual and
the energy balance fail; DEFECT_SPOOL_NO_SPEED_BRAKE leaves the regulating brake out of the
balance: the drum runs past the speed bound, and the residual and the energy fail.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from studies.reel_laws import DRUM, G, spool_energy  # noqa: E402
from tetherlab.deployment import simulate_reel  # noqa: E402
from tetherlab.scene import Scene  # noqa: E402

LIMITS = dict(mstar=5.0, omega=1.0, lc=10.0, k1=4.0, k2=1.0, max_torque=32.0, max_speed=1.5, gain=1000.0,
              EA=1e6, rtol=1e-10)  # fmt: skip


def limits_scene(*, duration="8 s", count=535, max_torque=None, max_speed=None) -> Scene:
    """The drum of 11.1 under the tension law with the torque and speed limits (module docstring).
    EA 1e6 N: the line's axial mode (~40 rad/s) is sampled ten times a period by the outputs, as in
    11.2, so that the works' trapezoid rule is in its asymptotic range."""
    d, c = DRUM, LIMITS
    reel = {"law": "tension", "exit": "drum", "rod_length": "200 m", "retire_length": "1 m",
            "stored_length": f"{d['stored']} m", "spool_inertia": f"{d['J']} kg m2", "drum_radius": f"{d['R']} m",
            "reduced_mass": f"{c['mstar']} kg", "orbit_rate": f"{c['omega']} rad/s",
            "commanded_length": f"{c['lc']} m", "k1": c["k1"], "k2": c["k2"],
            "max_torque": f"{c['max_torque'] if max_torque is None else max_torque} N m",
            "max_speed": f"{c['max_speed'] if max_speed is None else max_speed} m/s",
            "speed_brake_gain": f"{c['gain']} N s/m"}  # fmt: skip
    return Scene.from_dict({
        "name": "drum-limits", "duration": duration, "effects": {"uniform_gravity": {"g": f"{G} m/s2"}},
        "bodies": {"nail": {"fixed": True, "position": ["0 m", "0 m", "0 m"]},
                   "tip": {"mass": f"{d['M']} kg", "position": ["0 m", "0 m", f"-{d['L0']} m"],
                           "velocity": ["0 m/s", "0 m/s", "0 m/s"]}},
        "tethers": {"main": {"from": "nail", "to": "tip", "length": f"{d['L0']} m", "EA": f"{c['EA']} N",
                             "linear_density": f"{d['rho']} kg/m", "model": "energy", "reel": reel}},
        "integrator": {"method": "radau5", "rtol": c["rtol"], "atol": c["rtol"]},
        "output": {"count": count},
    })  # fmt: skip


def limits_run(defect: int = 0):
    return simulate_reel(limits_scene(), defect=defect, progress=False, raise_on_failure=False)


def limits_measure(run) -> dict:
    """The three bounds of the module docstring on a run of limits_scene: measured values and budgets."""
    c = LIMITS
    sp = limits_scene().tethers[0].reel.spool
    r = run.reel
    R = DRUM["R"]
    tau = r["torque_N_m"].to_numpy()
    ld = r["speed_m_s"].to_numpy()
    # the driving force the regulating brake must take at the fastest point: T - j - tau/R - F_f
    # (on a drum j = rho L'^2 eps: exit_jump_N is the canister's rho L'^2 (1 + eps), so form it here)
    eps = r["exit_speed_m_s"].to_numpy() / np.where(ld != 0.0, ld, 1.0) - 1.0
    jump = DRUM["rho"] * ld * ld * np.where(ld != 0.0, eps, 0.0)
    drive = r["exit_tension_N"].to_numpy() - jump - tau / R - r["friction_N"].to_numpy()
    ms = DRUM["J"] / R**2 + DRUM["rho"] * (DRUM["L0"] + DRUM["stored"] - r["deployed_length_m"].to_numpy())
    terms = (ms * r["accel_m_s2"].to_numpy(), r["exit_tension_N"].to_numpy(), jump, tau / R,
             r["friction_N"].to_numpy(), r["speed_brake_N"].to_numpy())  # fmt: skip
    residual = terms[0] - (terms[1] - terms[2] - terms[3] - terms[4] - terms[5])
    total, est = spool_energy(run)
    scale = float(np.abs(run.invariants["energy_J"]).max()) + float(r["spool_kinetic_J"].max())
    return {
        "torque": float(np.abs(tau).max()),
        "torque_command": float(np.abs(r["torque_command_N_m"]).max()),
        "torque_budget": sp.max_torque_N_m + sp.torque_limit_width_N_m * math.log(2.0),
        "speed": float(np.abs(ld).max()),
        "speed_budget": (sp.max_speed_m_s + max(float(drive.max()), 0.0) / sp.speed_brake_gain_N_s_m
                         + sp.speed_limit_width_m_s * math.log(2.0) + 10.0 * c["rtol"] * sp.max_speed_m_s),
        "residual": float(np.abs(residual).max()),
        "residual_budget": 1e3 * np.finfo(float).eps * float(np.abs(np.vstack(terms)).max()),
        "energy_drift": float(np.abs(total - total[0]).max()),
        "energy_budget": 2.0 * est + 100.0 * c["rtol"] * scale,
        "brake_work": float(r["brake_work_J"].iloc[-1]),
        "active": r["limit_active"].to_numpy(),
        "length": r["deployed_length_m"].to_numpy(),
        "t": r["t_s"].to_numpy(),
        "ok": run.ok,
    }
