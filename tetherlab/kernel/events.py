"""Event functions of a tethered system: where the right-hand side has a kink, or a run stops.

The integrators (tetherlab.integrators.driver.integrate with ``event=``) locate every change of
side of these components on their dense output, take the step exactly to it and restart there,
so no step ever straddles a kink.  Components, in this order (see :func:`event_components`):

* ``stop.altitude`` (terminal): |r_root| - (R + h_stop), present when the scene has
  ``[stop] altitude``; the run ends when the root body sinks below that altitude;
* one per rod of every ``tension_only`` tether: g = min(EA eps, EA eps + D eps').  The axial
  force max(0, EA eps + D eps') for eps > 0 (zero otherwise) switches exactly where g changes
  sign, so a tether going slack or snapping taut is a located event, not luck;
* one per rod of every inextensible tether (terminal): its tension multiplier lambda
  (tether/inextensible.py), from one evaluation of the right-hand side at (t, y).  The model
  holds only while it is positive: the run stops where a rod would go slack;
* four per reel under a spool law (terminal): its first rod's length at the birth bound and at
  the retirement bound (``reel.<tether>.birth``, ``reel.<tether>.retire``: the phase of the
  deployment ends there, tetherlab/deployment.py), the whole line paid out
  (``reel.<tether>.spent``: the run ends there, the end of the deployment), and the deployed
  length at the next stage's ``at_length`` (``reel.<tether>.stage``: the phase ends there and the
  next one runs under that stage, docs/deployment.md 10.7; a constant 1 when no such stage is
  pending, which never changes side);
* with the Cowell formulation (header H_EV_WHEELS), per wheel with a ``max_torque`` the torque
  limit max_torque - |command| and per wheel with a ``max_speed`` the speed cut-off
  (bodies/wheels.py::limit_events): negative while the limit acts, so saturation entered and left
  are located events.  Their values need the commanded torque, which the controller computes from
  the whole state: the right-hand side is evaluated once at (t, y) and the wheel scratch read.
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from .._jit import njit, rhs_cfunc
from ..bodies.wheels import limit_events
from ..tether.rod import strain
from ..tether.solve import system_accelerations
from .layout import (
    DEFECT_STAGE_FIRST_ROD,
    H_MUTANT,
    H_EV_WHEELS,
    H_NBODY,
    H_NWHEEL,
    H_OFF_BSCR,
    H_OFF_WT,
    TS_SIZE,
    BS_SIZE,
    WS_CMD,
    WS_SIZE,
    WS_SPEED,
    WT_MAXT,
    WT_MAXW,
    WT_SIZE,
    H_EV_STOP_R,
    H_NQT,
    H_LEN,
    H_NSTATE,
    H_NREEL,
    H_NTETH,
    H_OFF_REEL,
    H_OFF_ROD,
    RL_FIXED,
    RL_LBIRTH,
    RL_LINE,
    RL_LRETIRE,
    RL_LSTAGE,
    RL_SIZE,
    RL_SOFF,
    H_OFF_TETH,
    RT_D,
    RT_EA,
    RT_LU,
    RT_SIZE,
    TT_NRODS,
    TT_ROD0,
    TT_SIZE,
    TT_TENSION_ONLY,
    TT_MODEL,
    MODEL_INEXT,
    H_OFF_SCR,
    SR_FE,
    SR_SIZE,
)

SQ3 = math.sqrt(3.0)


@njit(cache=True)
def event_values(t, y, g_ptr, p):
    """The event components of the Cowell state y (length p[H_NSTATE]) into g_ptr[0..]; also
    called by other formulations on the Cowell state they rebuild (formulations/dromo.py)."""
    n = int(p[H_NSTATE])
    h = int(p[H_NQT])  # q_trans' starts here (state-layout descriptor; attitude blocks follow)
    k = 0
    r_stop = p[H_EV_STOP_R]
    if r_stop > 0.0:
        g_ptr[0] = math.sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]) - r_stop
        k = 1
    offt = int(p[H_OFF_TETH])
    offr = int(p[H_OFF_ROD])
    for tt in range(int(p[H_NTETH])):
        tb = offt + tt * TT_SIZE
        if p[tb + TT_TENSION_ONLY] == 0.0:
            continue
        g0 = int(p[tb + TT_ROD0])
        for g in range(g0, g0 + int(p[tb + TT_NRODS])):
            rb = offr + g * RT_SIZE
            dx = y[3 + 3 * g]
            dy = y[4 + 3 * g]
            dz = y[5 + 3 * g]
            dn = math.sqrt(dx * dx + dy * dy + dz * dz)
            lu = p[rb + RT_LU]
            ea = p[rb + RT_EA]
            eps = strain(dn, lu)
            el = ea * eps
            damp = p[rb + RT_D]
            if damp != 0.0 and dn > 0.0:
                epsd = 2.0 * SQ3 * (dx * y[h + 3 + 3 * g] + dy * y[h + 4 + 3 * g] + dz * y[h + 5 + 3 * g]) / (dn * lu)
                el = min(el, el + damp * epsd)
            g_ptr[k] = el
            k += 1
    inext = False
    for tt in range(int(p[H_NTETH])):
        if int(p[offt + tt * TT_SIZE + TT_MODEL]) == MODEL_INEXT:
            inext = True
    if p[H_EV_WHEELS] != 0.0 or inext:
        nw = int(p[H_NWHEEL])
        acc = np.empty(h)
        datt = np.empty(n - 2 * h)
        code = system_accelerations(t, y[:h], y[h : 2 * h], y[2 * h : n], p, acc, datt)
        if code != 0:
            return code
    if inext:  # every rod's tension multiplier (tether/inextensible.py), terminal at zero
        scr = int(p[H_OFF_SCR])
        for tt in range(int(p[H_NTETH])):
            tb = offt + tt * TT_SIZE
            if int(p[tb + TT_MODEL]) != MODEL_INEXT:
                continue
            g0 = int(p[tb + TT_ROD0])
            for g in range(g0, g0 + int(p[tb + TT_NRODS])):
                g_ptr[k] = p[scr + g * SR_SIZE + SR_FE]
                k += 1
    for i in range(int(p[H_NREEL])):  # a spool law's first rod at its birth and retirement bounds
        rb = int(p[H_OFF_REEL]) + i * RL_SIZE
        so = int(p[rb + RL_SOFF])
        if so < 0:
            continue
        l = y[2 * h + so] - p[rb + RL_FIXED]
        g_ptr[k] = l - p[rb + RL_LBIRTH]
        g_ptr[k + 1] = l - p[rb + RL_LRETIRE]
        g_ptr[k + 2] = p[rb + RL_LINE] - y[2 * h + so]
        stage_l = y[2 * h + so]
        if int(p[H_MUTANT]) == DEFECT_STAGE_FIRST_ROD:  # negative control of the stage's location
            stage_l = l
        g_ptr[k + 3] = stage_l - p[rb + RL_LSTAGE] if p[rb + RL_LSTAGE] > 0.0 else 1.0
        k += 4
    if p[H_EV_WHEELS] != 0.0:
        nw = int(p[H_NWHEEL])
        wscr = int(p[H_OFF_BSCR]) + int(p[H_NBODY]) * BS_SIZE + int(p[H_NTETH]) * TS_SIZE
        offw = int(p[H_OFF_WT])
        for j in range(nw):
            wb = offw + j * WT_SIZE
            g_t, g_w = limit_events(p, wb, p[wscr + j * WS_SIZE + WS_CMD], p[wscr + j * WS_SIZE + WS_SPEED])
            if p[wb + WT_MAXT] > 0.0:
                g_ptr[k] = g_t
                k += 1
            if p[wb + WT_MAXW] > 0.0:
                g_ptr[k] = g_w
                k += 1
    return 0


@rhs_cfunc
def system_events(t, y_ptr, g_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    return event_values(t, carray(y_ptr, (int(p[H_NSTATE]),)), g_ptr, p)


def event_components(model, stop_radius_m: float = 0.0, wheel_limits: bool = False) -> tuple[list[str], list[bool]]:
    """Names and terminal flags of the components :func:`system_events` writes for ``model``
    (whose p must have H_EV_STOP_R set to ``stop_radius_m`` and H_EV_WHEELS to ``wheel_limits``)."""
    names, terminal = [], []
    if stop_radius_m > 0.0:
        names.append("stop.altitude")
        terminal.append(True)
    for t, sl in zip(model.tethers, model.rod_slices):
        if getattr(t, "tension_only", False):
            for i in range(sl.stop - sl.start):
                names.append(f"slack.{t.name}.rod{i + 1}")
                terminal.append(False)
    for t, sl in zip(model.tethers, model.rod_slices):
        if getattr(t, "model", "") == "inextensible":
            for i in range(sl.stop - sl.start):
                names.append(f"inextensible.{t.name}.rod{i + 1}")
                terminal.append(True)
    for k in model.state.spools:  # terminal: a birth or retirement ends the phase (deployment.py)
        n = model.tethers[k].name
        names.extend([f"reel.{n}.birth", f"reel.{n}.retire", f"reel.{n}.spent", f"reel.{n}.stage"])
        terminal.extend([True, True, True, True])
    if wheel_limits:
        for b in model.bodies:  # kernel body order, wheels in file order: the wheel table's order
            rig = getattr(b, "rigid", None)
            for w in (rig.wheels if rig is not None else ()):
                if w.max_torque_N_m > 0.0:
                    names.append(f"wheel.{b.name}.{w.name}.max_torque")
                    terminal.append(False)
                if w.max_speed_rad_s > 0.0:
                    names.append(f"wheel.{b.name}.{w.name}.max_speed")
                    terminal.append(False)
    return names, terminal
