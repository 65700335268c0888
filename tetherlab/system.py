"""From validated SI values to the compiled model: the parameter block, the state layout, the
initial state and the per-component tolerance scales.

This is the only place that knows both the boundary objects and the parameter block, which it
writes through the schema's typed view (``tetherlab/model/params.py``).  Nothing here is called
per right-hand-side evaluation.
"""

from __future__ import annotations

import functools

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .bodies.registry import part_of
from .tether.registry import part_of as tether_part_of
from .forces.registry import EffectSpec
from .model import params as P
from .model import topology
from .model.state import StateLayout

SQ3 = np.sqrt(3.0)

#: Strain at which a rod counts as collapsed and the run stops with an error: at eps = -1 the rod
#: has zero length and its direction u is undefined (eq. 8), so the model itself breaks down well
#: before.  -0.9 leaves room for legitimate compression of a slack-free elastic tether.
MIN_STRAIN = -0.9


@dataclass(frozen=True)
class ReelSpec:
    """A reel paying a tether out at its end A_1 (SI; docs/deployment.md).  The law gives the
    deployed unstretched length L(t) from ``length0_m`` at t = 0; ``line_length_m`` is deployed
    plus stored at t = 0.  The tether's first rod has length L(t) minus its other rods', each of
    ``rod_length_m``."""

    law: str  # "constant" | "exponential"
    exit: str  # "canister" | "drum"
    length0_m: float
    speed_m_s: float
    rate_1_s: float
    rod_length_m: float
    density_kg_m: float
    line_length_m: float
    table: tuple = ()  # law "table": per interval (t_k, a0, a1, a2, a3), L = a0 + a1 s + a2 s^2 + a3 s^3
    # on a rigid body: the stored tether is a thin ring of this radius about this axis (body axes, unit;
    # a canister's is its exit direction), centred at the exit (docs/deployment.md 9)
    spool_radius_m: float = 0.0
    spool_axis: tuple = (0.0, 0.0, 0.0)
    # laws "spool" and "tension" (tether/reel_spool.py): speed_m_s is L'(0); the spool and its friction
    spool_mass_kg: float = 0.0  # J/R^2
    radius_m: float = 0.0
    torque_N_m: float = 0.0  # positive hauling in
    viscous_N_s_m: float = 0.0
    coulomb_N: float = 0.0
    friction_speed_m_s: float = 1.0
    # law "tension": T_c = m* Omega^2 [3 l_c + k1 (L - l_c) + k2 L'/Omega], smoothly limited
    mstar_kg: float = 0.0
    omega_rad_s: float = 0.0
    lc_m: float = 0.0
    k1: float = 0.0
    k2: float = 0.0
    tmin_N: float = 0.0
    tmax_N: float = 0.0
    twidth_N: float = 0.0  # 0: no limits
    # the spool laws' smooth limits on the motor's torque and on the pay-out speed (10.4)
    max_torque_N_m: float = 0.0  # 0: none
    torque_width_N_m: float = 0.0
    max_speed_m_s: float = 0.0
    speed_gain_N_s_m: float = 0.0
    speed_width_m_s: float = 0.0  # 0: no speed limit
    birth_length_m: float = 0.0  # the first rod's bounds: located events under a spool law
    retire_length_m: float = 0.0


@dataclass(frozen=True)
class TetherSpec:
    """One tether in SI units (already validated by the scene layer)."""

    name: str
    rods: int
    length_m: float
    ea_n: float
    mass_kg: float
    damping_n_s: float = 0.0
    model: str = "paper"  # "paper" | "energy"
    tip_mass_kg: float = 0.0  # 0: free end (no tip body)
    tip_name: str = ""
    diameter_m: float | None = None  # for effects on the tether's cross-section (drag); None: unknown
    tension_only: bool = False  # no axial force in compression (slack tether)
    parent: str = ""  # body at end A_1 in the kernel (the root side); "" = the model's root
    from_point_m: tuple = (0.0, 0.0, 0.0)  # attachment of A_1 on the parent, body axes (rigid)
    to_point_m: tuple = (0.0, 0.0, 0.0)  # attachment of B_n on the child, body axes (rigid)
    reversed: bool = False  # the scene writes it child -> parent: outputs flip it back
    part: str = ""  # its part type (tether/registry.py); "": the rod chain
    # a reel at A_1: length_m is then the deployed length at the model's start, the first rod
    # takes what the others (of reel.rod_length_m each) leave of it
    reel: ReelSpec | None = None
    # model "inextensible" (part "inextensible"): Baumgarte rate of the rods' length constraints
    constraint_rate_1_s: float = 0.0


@dataclass(frozen=True)
class WheelSpec:
    """A momentum wheel (SI, validated by the scene layer; docs/model.md section 12)."""

    name: str
    axis: tuple  # unit vector, body axes
    inertia_kg_m2: float
    speed_rad_s: float = 0.0  # initial spin relative to the body
    max_speed_rad_s: float = 0.0  # 0: no limit
    max_torque_N_m: float = 0.0  # 0: no limit
    mode: str = "constant"  # "constant" | "table" | "control"
    torque_N_m: float = 0.0
    times_s: tuple = ()
    values_N_m: tuple = ()


@dataclass(frozen=True)
class ControlSpec:
    target: str  # "orbit" | "inertial"
    kp_N_m: float
    kd_N_m_s: float
    quaternion: tuple = (1.0, 0.0, 0.0, 0.0)  # inertial target (w, x, y, z)


@dataclass(frozen=True)
class RigidSpec:
    inertia_kg_m2: tuple  # J_B about G, body axes, wheels locked (3x3 nested tuple)
    wheels: tuple = ()  # WheelSpec
    control: ControlSpec | None = None


@dataclass(frozen=True)
class BodySpec:
    """A body of the kernel (kernel order: docs/scenes.md)."""

    name: str
    mass_kg: float
    fixed: bool = False
    rigid: RigidSpec | None = None
    part: str = ""  # its part type (bodies/registry.py); "": rigid with a rigid table, else point


@dataclass
class Model:
    """The compiled model of one scene: parameter block and state layout."""

    p: np.ndarray
    root_mass_kg: float
    root_fixed: bool
    tethers: list[TetherSpec]
    effect_names: list[str]
    effect_codes: list[int]
    quadrature: int
    root_name: str = "m0"
    rod_slices: list[slice] = field(default_factory=list)  # global rod indices of each tether
    effect_meta: dict = field(default_factory=dict)  # what effects report at pack time (fit errors)
    bodies: list = field(default_factory=list)  # BodySpec in kernel order ("" names: free ends)
    roots: list = field(default_factory=list)  # kernel indices of the root bodies
    rigid_index: dict = field(default_factory=dict)  # body index -> attitude offset in y
    wheel_index: dict = field(default_factory=dict)  # (body index, wheel name) -> state index
    state: Any = None  # tetherlab.model.state.StateLayout: the named blocks of y (set by build_model)

    @property
    def n_qt(self) -> int:
        """Length of q_trans (the second-order part: y = [q_trans, q_trans', attitude, wheels])."""
        return P.ParamView(self.p).n_qtrans

    @property
    def has_attitude(self) -> bool:
        return self.state.has_attitude

    def root_offset(self, b: int) -> int:
        """Index in q_trans of root body b's position."""
        return P.ParamView(self.p).body(b).qtrans_index

    @property
    def n_rods(self) -> int:
        return P.ParamView(self.p).n_rods

    @property
    def n_state(self) -> int:
        return P.ParamView(self.p).n_state

    def breakpoints_s(self) -> np.ndarray:
        """Every corner and jump of the model's time tables (the wheel torque tables), sorted,
        each once: where the right-hand side has a kink or a jump in time, so the integrators land
        a step on each and restart there (docs/integrators.md section 14)."""
        times = [x for b in self.bodies if getattr(b, "rigid", None) is not None
                 for w in b.rigid.wheels for x in w.times_s]  # fmt: skip
        return np.unique(np.asarray(times, dtype=float))

    def fresh_params(self) -> np.ndarray:
        """A copy of the parameter block (the kernel writes scratch and counters into it)."""
        return self.p.copy()

    def rod_masses(self) -> np.ndarray:
        return P.ParamView(self.p).rods.mass_kg.copy()

    def rod_lengths(self) -> np.ndarray:
        return P.ParamView(self.p).rods.length_m.copy()

    def total_mass(self) -> float:
        return sum(b.mass_kg for b in self.bodies if not b.fixed) + sum(t.mass_kg for t in self.tethers)


def gauss_legendre_halves(nq: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes xi and weights for the two half rods [-1, 0] and [0, 1]; each half's weights sum to 1.
    (Copies of one computation per nq: a deployment builds a model at every birth.)"""
    nodes, weights = _gauss_legendre_halves(int(nq))
    return nodes.copy(), weights.copy()


@functools.lru_cache(maxsize=None)
def _gauss_legendre_halves(nq: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(nq)
    right = 0.5 * (1.0 + x)
    wr = 0.5 * w
    nodes = np.concatenate([-right[::-1], right])
    weights = np.concatenate([wr[::-1], wr])
    return nodes, weights


def _hot_slots() -> dict:
    """Effect code -> header field of its parameter offset, for the point-mass effects that
    kernel/effects.py::_body_force evaluates without walking the effect table."""
    from .forces import central_gravity, stiefel_moon, zonal

    return {central_gravity.CODE: "central_gravity_par", zonal.CODE_J2: "j2_par", stiefel_moon.CODE: "stiefel_moon_par"}


_HOT_SLOTS = _hot_slots()


def build_model(
    *,
    root_mass_kg: float,
    tethers: list[TetherSpec],
    effects: list[tuple[EffectSpec, dict]],
    central: dict,
    quadrature: int = 2,
    root_fixed: bool = False,
    root_name: str = "m0",
    epoch: str | None = None,
    duration_s: float | None = None,
    bodies: list[BodySpec] | None = None,
    defect: int = P.DEFECT_NONE,
    graph=None,
) -> Model:
    """Pack the parameter block.  Inputs are SI floats that the scene layer has validated.

    ``epoch`` (ISO date, TDB) and ``duration_s`` are for time-dependent effects (ephemerides fitted
    over the run); effects that do not need them ignore them.

    ``bodies``: the bodies in kernel order (docs/scenes.md: 0 the first root, 1 + k the child end
    of tether k, then the other roots); each tether's ``parent`` names its root-side body.
    Without it: the star of the original API (a root named ``root_name`` carrying every tether,
    tips of ``tip_mass_kg``; a tip mass of 0 is a free end).  ``defect``: negative controls only.
    ``graph``: the scene's graph (tetherlab/model/topology.py) the bodies were ordered by, whose
    elimination order the kernel runs; without it, the same order derived from the parents.
    """
    nteth = len(tethers)
    nrods = sum(t.rods for t in tethers)
    if bodies is None:
        bodies = [BodySpec(root_name, 0.0 if root_fixed else root_mass_kg, root_fixed)] + [
            BodySpec(t.tip_name, t.tip_mass_kg) for t in tethers
        ]
        tethers = [t if t.parent else _with_parent(t, root_name) for t in tethers]
    names = [b.name for b in bodies]
    index = {b.name: i for i, b in enumerate(bodies) if b.name}
    nbody = len(bodies)
    if nbody < 1 + nteth:
        raise ValueError("bodies: expected 1 + one per tether (its child end) + the other roots")
    roots = [0] + list(range(1 + nteth, nbody))
    # the state's named blocks: the header's state offsets below are read from them
    state = StateLayout.from_parts(tethers, bodies, roots)
    rigid = [b for b, _ in state.rigid]
    wheels = [(b, w) for b in rigid for w in bodies[b].rigid.wheels]

    # What an effect with per-body or per-tether parameters needs to lay them out in kernel order:
    # body index 0 is the root, 1 + k the child end of tether k (the ``body`` argument of body_force).
    ctx = {
        "bodies": names,
        "tethers": list(tethers),
        "root_fixed": root_fixed,
        "epoch": epoch,
        "duration_s": duration_s,
        "meta": {},  # effects put what the result's meta should report here (by effect name)
    }
    eff_params: list[list[float]] = [
        list(spec.pack(params, central, ctx)) if spec.pack else [] for spec, params in effects
    ]
    wheel_table_floats = sum(2 * len(w.times_s) for _, w in wheels)
    n_rest = sum(1 for spec, _ in effects if spec.code not in _HOT_SLOTS)
    dims = P.dims_of(
        n_rods=nrods, n_tethers=nteth, n_bodies=nbody, n_wheels=len(wheels), n_effects=len(effects),
        n_effect_pars=sum(len(x) for x in eff_params), n_quadrature=quadrature, n_roots=len(roots), n_rest=n_rest,
        n_wheel_table_floats=wheel_table_floats,
    )
    reels = [k for k, t in enumerate(tethers) if t.reel is not None]
    dims["n_reels"] = len(reels)
    dims["n_reel_table_floats"] = sum(5 * len(tethers[k].reel.table) for k in reels)
    offs, length = P.block_offsets(dims)
    p = np.zeros(length)
    P.write_table_offsets(p, offs)
    v = P.ParamView(p)
    v.block_length = length
    v.n_state = state.size
    v.formulation = P.FORM_COWELL
    v.n_rods = nrods
    v.n_reels = len(reels)
    tab = v.part_offset("reels", "tables")
    for i, k in enumerate(reels):  # the table laws' intervals, before anything sizes past them
        rows = tethers[k].reel.table
        v.reel(i).table_offset = tab
        v.reel(i).table_intervals = len(rows)
        p[tab : tab + 5 * len(rows)] = np.asarray(rows, float).ravel() if rows else []
        tab += 5 * len(rows)
    v.n_tethers = nteth
    v.root_inv_mass_1_kg = 0.0 if root_fixed else 1.0 / root_mass_kg
    v.root_mass_kg = 0.0 if root_fixed else root_mass_kg
    v.n_effects = len(effects)
    v.n_quadrature = quadrature
    v.fail_rod = -1
    v.min_strain = MIN_STRAIN
    v.interval_end_s = -1.0  # no breakpoint: tables right-continuous (the driver sets it while integrating)
    v.n_qtrans = state.n_qt
    v.attitude_index = state.attitude.start
    v.n_rigid = len(rigid)
    v.wheel_state_index = state.wheels.start
    v.n_wheels = len(wheels)
    v.n_bodies = nbody
    v.n_roots = len(roots)
    v.defect = defect
    # the gravity-gradient torque acts where central_gravity acts (docs/model.md section 12)
    v.mu_gg_m3_s2 = central["mu_m3_s2"] if any(spec.name == "central_gravity" for spec, _ in effects) else 0.0
    v.roots[:] = roots

    # effect table, parameters after the table; the body-force fields (central_gravity_par ...)
    par = v.part_offset("effects", "pars")
    for slot in _HOT_SLOTS.values():
        setattr(v, slot, -1)
    v.n_rest = n_rest
    rest = v.rest
    n_rest = 0
    for e, ((spec, _), vals) in enumerate(zip(effects, eff_params)):
        tv = v.effect(e)
        tv.code = spec.code
        tv.par_offset = par
        tv.n_par = len(vals)
        p[par : par + len(vals)] = vals
        if spec.code in _HOT_SLOTS:
            setattr(v, _HOT_SLOTS[spec.code], par)
        else:
            rest[n_rest] = spec.code, par
            n_rest += 1
        par += len(vals)

    rod_slices = []
    g = 0
    for k, t in enumerate(tethers):
        tv = v.tether(k)
        tv.n_rods = t.rods
        tv.rod0 = g
        tv.tip_inv_mass_1_kg = 1.0 / t.tip_mass_kg if t.tip_mass_kg > 0 else 0.0
        tv.tip_mass_kg = t.tip_mass_kg
        tv.model = {"paper": P.MODEL_PAPER, "energy": P.MODEL_ENERGY, "printed": P.MODEL_PRINTED,
                    "inextensible": P.MODEL_INEXT}[t.model]
        tv.tension_only = 1.0 if t.tension_only else 0.0
        tv.parent = index[t.parent]
        tv.child = 1 + k if bodies[1 + k].name and bodies[1 + k].mass_kg > 0 else -1
        tv.parent_point_m = t.from_point_m
        tv.part = tether_part_of(t).code  # the TT_PART slot the tether dispatcher reads
        rod_slices.append(slice(g, g + t.rods))
        if t.reel is not None:
            _write_reel(v, reels.index(k), k, index[t.parent], g, t, bodies[index[t.parent]].mass_kg, state)
        for j in range(t.rods):
            rv = v.rod(g)
            if t.reel is not None:  # the first rod varies, the others are full rods (docs/deployment.md)
                lj = t.length_m - (t.rods - 1) * t.reel.rod_length_m if j == 0 else t.reel.rod_length_m
                rv.mass_kg = t.reel.density_kg_m * lj
                rv.length_m = lj
            else:
                # equal rods: each has L_u/n and m_t/n (paper section 2.2 allows any split)
                rv.mass_kg = t.mass_kg / t.rods
                rv.length_m = t.length_m / t.rods
            rv.ea_N = t.ea_n
            rv.damping_N_s = t.damping_n_s
            rv.tether = k
            rv.constraint_rate_1_s = t.constraint_rate_1_s
            g += 1

    nodes, weights = gauss_legendre_halves(quadrature)
    v.quadrature_nodes[:] = nodes
    v.quadrature_weights[:] = weights

    # bodies: parents, elimination order (leaves first), attitude and wheel blocks
    parent_tether = {1 + k: k for k in range(nteth)}
    if graph is not None:
        order = list(graph.elimination_order)
    else:
        _, order = topology.depths_and_order(nbody, [index[t.parent] for t in tethers])
    p[offs["order"] : offs["order"] + nteth] = order
    rigid_index = {}
    wheel_index = {}
    tab = v.part_offset("wheels", "tables")
    for b, body in enumerate(bodies):
        bv = v.body(b)
        fixed = body.fixed or not body.mass_kg > 0
        bv.mass_kg = 0.0 if fixed else body.mass_kg
        bv.inv_mass_1_kg = 0.0 if fixed else 1.0 / body.mass_kg
        for k in reels:  # the stored tether is part of its body's mass (tether/reel.py keeps it so)
            t = tethers[k]
            if t.parent == body.name and not fixed:
                bv.mass_kg = body.mass_kg + t.reel.density_kg_m * (t.reel.line_length_m - t.length_m)
                bv.inv_mass_1_kg = 1.0 / bv.mass_kg
                if b == 0:
                    v.root_mass_kg = bv.mass_kg
                    v.root_inv_mass_1_kg = bv.inv_mass_1_kg
        bv.qtrans_index = state.root_offset(b) if b == 0 or b > nteth else -1
        bv.parent = parent_tether.get(b, -1)
        bv.attitude_index = -1
        bv.n_children = sum(1 for t in tethers if t.parent == body.name and body.name)
        if 1 <= b <= nteth:
            bv.child_point_m = tethers[b - 1].to_point_m
        bv.rigid = float(part_of(body).code)  # the BT_PART slot the part dispatcher reads
        if body.rigid is None:
            continue
        rs = body.rigid
        bv.attitude_index = rigid_index[b] = state.attitude_of(b).start
        JB = np.asarray(rs.inertia_kg_m2, float)
        JS = JB.copy()
        bv.wheel0 = len(wheel_index)
        bv.n_wheels = len(rs.wheels)
        ctrl = [w for w in rs.wheels if w.mode == "control"]
        pinv = np.linalg.pinv(np.array([w.axis for w in ctrl], float).T) if ctrl else None
        for w in rs.wheels:
            j = len(wheel_index)
            wheel_index[(b, w.name)] = state.wheels.start + j
            a = np.asarray(w.axis, float)
            JS -= w.inertia_kg_m2 * np.outer(a, a)
            wv = v.wheel(j)
            wv.body = b
            wv.axis = a
            wv.inertia_kg_m2 = w.inertia_kg_m2
            wv.mode = {"constant": P.WMODE_CONST, "table": P.WMODE_TABLE, "control": P.WMODE_CONTROL}[w.mode]
            wv.torque_N_m = w.torque_N_m
            wv.max_speed_rad_s = w.max_speed_rad_s
            wv.max_torque_N_m = w.max_torque_N_m
            wv.torque_limit_lock = -1.0  # decided per evaluation until the driver locks it
            wv.speed_limit_lock = -1.0
            if w.mode == "table":
                nt = len(w.times_s)
                wv.table_offset = tab
                wv.table_points = nt
                p[tab : tab + nt] = w.times_s
                p[tab + nt : tab + 2 * nt] = w.values_N_m
                tab += 2 * nt
            if w.mode == "control":
                wv.pinv_row = pinv[ctrl.index(w)]
        bv.js_kg_m2 = JS.ravel()
        bv.jb_kg_m2 = JB.ravel()
        if rs.control is not None:
            c = rs.control
            bv.control = P.CTRL_ORBIT if c.target == "orbit" else P.CTRL_INERTIAL
            bv.kp_N_m = c.kp_N_m
            bv.kd_N_m_s = c.kd_N_m_s
            bv.target_quaternion = c.quaternion

    model = Model(
        p=p,
        root_mass_kg=root_mass_kg,
        root_fixed=root_fixed,
        tethers=list(tethers),
        effect_names=[s.name for s, _ in effects],
        effect_codes=[s.code for s, _ in effects],
        quadrature=quadrature,
        root_name=root_name,
        rod_slices=rod_slices,
        effect_meta=ctx["meta"],
        bodies=list(bodies),
        roots=roots,
        rigid_index=rigid_index,
        wheel_index=wheel_index,
    )
    model.state = state
    return model


def _write_reel(v, i: int, k: int, body: int, g0: int, t: TetherSpec, body_mass_kg: float, layout) -> None:
    """Reel i's row of the block (tether/reel.py reads it every evaluation)."""
    r = t.reel
    rv = v.reel(i)
    rv.tether = k
    rv.body = body
    rv.rod = g0
    rv.law = {"constant": P.REEL_LAW_CONSTANT, "exponential": P.REEL_LAW_EXPONENTIAL, "table": P.REEL_LAW_TABLE,
              "spool": P.REEL_LAW_SPOOL, "tension": P.REEL_LAW_TENSION}[r.law]  # fmt: skip
    # a spool law's [L, L'] in the first-order block the kernel gets (tether/reel.py reads it there)
    rv.state_offset = layout.spool_of(k).start - layout.first_order.start if k in layout.spools else -1
    for name in ("spool_mass_kg", "radius_m", "torque_N_m", "viscous_N_s_m", "coulomb_N", "friction_speed_m_s",
                 "mstar_kg", "omega_rad_s", "lc_m", "k1", "k2", "tmin_N", "tmax_N"):
        setattr(rv, name, getattr(r, name))
    rv.twidth_N = r.twidth_N
    rv.max_torque_N_m = r.max_torque_N_m
    rv.torque_width_N_m = r.torque_width_N_m
    rv.max_speed_m_s = r.max_speed_m_s
    rv.speed_gain_N_s_m = r.speed_gain_N_s_m
    rv.speed_width_m_s = r.speed_width_m_s
    rv.birth_m = r.birth_length_m
    rv.retire_m = r.retire_length_m
    rv.exit = {"canister": P.REEL_EXIT_CANISTER, "drum": P.REEL_EXIT_DRUM}[r.exit]
    rv.length0_m = r.length0_m
    rv.speed_m_s = r.speed_m_s
    rv.rate_1_s = r.rate_1_s
    rv.fixed_length_m = (t.rods - 1) * r.rod_length_m
    rv.density_kg_m = r.density_kg_m
    rv.body_mass_kg = body_mass_kg
    rv.line_length_m = r.line_length_m
    rv.spool_radius_m = r.spool_radius_m
    rv.spool_axis = r.spool_axis
    v.tether(k).reel = i + 1


def _with_parent(t: TetherSpec, parent: str) -> TetherSpec:
    from dataclasses import replace

    return replace(t, parent=parent)


def chain_state(
    model: Model,
    r0: np.ndarray,
    v0: np.ndarray,
    rod_dirs: list[np.ndarray],
    strains: list[float],
    omega: np.ndarray | None,
) -> np.ndarray:
    """Initial state from the root position/velocity and each rod's direction and strain.

    ``rod_dirs[k]`` is an (n_k, 3) array of unit vectors along the rods of tether k (from the
    root side to the tip side).  The whole system moves rigidly: translation with v0 plus rotation
    with angular velocity ``omega`` (None: pure translation), so d_i' = omega x d_i.  Other roots
    start at the origin at rest; the attitude block (if any) at the identity, at rest, and the
    wheels at their initial speeds (:func:`attitude_block`).
    """
    lay = model.state
    y = np.zeros(lay.size)
    y[lay.root_r] = r0
    y[lay.root_v] = v0
    lengths = model.rod_lengths()
    w = np.zeros(3) if omega is None else np.asarray(omega, float)
    for k, _ in enumerate(model.tethers):
        sl = model.rod_slices[k]
        dirs = np.asarray(rod_dirs[k], float).reshape(-1, 3)
        norms = np.array([np.linalg.norm(dj) for dj in dirs])  # each as a 3-vector's norm
        d = (dirs / norms[:, None]) * lengths[sl, None] * (1.0 + strains[k]) / (2.0 * SQ3)  # eq. 3
        dd = np.cross(w, d)  # elementwise: the same numbers as one rod at a time
        for j, g in enumerate(range(sl.start, sl.stop)):
            y[lay.rod(g)] = d[j]
            y[lay.rod_rate(g)] = dd[j]
    y[lay.first_order] = attitude_block(model, {})
    return y


def attitude_block(model: Model, states: dict) -> np.ndarray:
    """The attitude and wheel block of y: per rigid body (kernel order) its quaternion (w, x, y, z,
    body -> inertial) and omega (body axes) from ``states[b] = (q, omega_b)`` (default identity, at
    rest); per wheel its axial momentum h = I (a . omega_b + Omega_0) (bodies/wheels.py)."""
    out = []
    wheels = []
    for b in sorted(model.rigid_index):
        qb, wb = states.get(b, ((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
        out.extend(qb)
        out.extend(wb)
        for w in model.bodies[b].rigid.wheels:
            wheels.append(w.inertia_kg_m2 * (float(np.dot(w.axis, wb)) + w.speed_rad_s))
    spools = []  # a spool-law reel's [L, L'] at the model's start
    for k in model.state.spools:
        r = model.tethers[k].reel
        spools.extend([model.tethers[k].length_m, r.speed_m_s])
    return np.array(out + wheels + spools, float)


def _state_parts(model: Model, y: np.ndarray):
    lay = model.state
    y = np.ascontiguousarray(y, float)
    return y[lay.q], y[lay.qd], y[lay.first_order]


def point_positions(model: Model, y: np.ndarray) -> dict:
    """Inertial positions/velocities of the bodies, rod centres, joints and tips for one state
    (eq. 23), from the compiled kinematics of the forest (tether/chain.py: forward)."""
    from .tether.solve import joint_states

    nr = model.n_rods
    q, qd, att = _state_parts(model, y)
    p = model.fresh_params()
    nj = nr + len(model.tethers)
    out = np.zeros((nj, 6))
    bodies = np.zeros((len(model.bodies), 6))
    rot = np.zeros((len(model.bodies), 9))
    joint_states(q, qd, att, p, out, bodies, rot)
    # q and q' start where y and its q' half start, so the rods' block slices them both
    d = q[model.state.rods_d].reshape(nr, 3)
    dd = qd[model.state.rods_d].reshape(nr, 3)
    rG = np.zeros((nr, 3))
    vG = np.zeros((nr, 3))
    joints = []  # per tether: (n_k + 1, 3) positions of A_1, B_1, ..., B_n (kernel order)
    jvel = []
    for k, sl in enumerate(model.rod_slices):
        block = out[sl.start + k : sl.stop + k + 1]
        joints.append(block[:, :3].copy())
        jvel.append(block[:, 3:].copy())
        rG[sl.start : sl.stop] = block[:-1, :3] + SQ3 * d[sl.start : sl.stop]
        vG[sl.start : sl.stop] = block[:-1, 3:] + SQ3 * dd[sl.start : sl.stop]
    return {
        "r0": bodies[0, :3].copy(), "v0": bodies[0, 3:].copy(), "d": d, "dd": dd, "rG": rG, "vG": vG,
        "joints": joints, "jvel": jvel, "bodies": bodies, "rotations": rot.reshape(-1, 3, 3),
    }


def center_of_mass(model: Model, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pts = point_positions(model, y)
    m = model.rod_masses()
    M = 0.0
    r = np.zeros(3)
    v = np.zeros(3)
    for b, body in enumerate(model.bodies):
        if body.fixed or not body.mass_kg > 0 or not body.name:
            continue
        M += body.mass_kg
        r += body.mass_kg * pts["bodies"][b, :3]
        v += body.mass_kg * pts["bodies"][b, 3:]
    M += m.sum()
    r += m @ pts["rG"]
    v += m @ pts["vG"]
    return r / M, v / M


def tolerance_scales(model: Model, ref_length_m: float, ref_time_s: float) -> np.ndarray:
    """Natural scale of each state component: atol_i = atol * scale_i (atol in scale units).

    Root positions: the orbit radius; their velocities: radius/time unit; d_i: the rod's half
    TMED separation L_u/(2 sqrt 3); d_i': that over the time unit.  So a scene's atol = 1e-10
    means 1e-10 of each quantity's own size, not 1e-10 m on a 7000 km orbit radius.  Quaternion
    components: 1; body rates: 1/time unit; wheel momenta: I_k times the larger of 1/time unit and
    the wheel's speed limit or initial speed.
    """
    lay = model.state
    lengths = model.rod_lengths()
    s = np.empty(lay.size)
    s[lay.q] = float(ref_length_m)
    for g in range(lay.n_rods):
        s[lay.rod(g)] = lengths[g] / (2 * SQ3)
    s[lay.qd] = s[lay.q] / ref_time_s
    att = []
    wheels = []
    for b in sorted(model.rigid_index):
        att.extend([1.0] * 4 + [1.0 / ref_time_s] * 3)
        for w in model.bodies[b].rigid.wheels:
            wheels.append(w.inertia_kg_m2 * max(1.0 / ref_time_s, abs(w.speed_rad_s), w.max_speed_rad_s))
    for k in lay.spools:  # a spool's length and rate on the scale of its tether
        att_len = model.tethers[k].reel.line_length_m
        wheels.extend([att_len, att_len / ref_time_s])
    s[lay.first_order] = np.array(att + wheels, float)
    return s


def tether_error_floor(model: Model, ref_time_s: float) -> np.ndarray:
    """Per-component floor that measures the rods' error against their whole tether's length.

    d_i: L_tether/(2 sqrt 3), the half TMED separation of the tether as one rod; d_i': that over
    the time unit; every other component: 0.  The pipeline adds rtol times this to the absolute
    tolerance (integrator.error_scale = "tether"), so the relative part of a rod's error test no
    longer shrinks with the rod (docs/integrators.md section 15).
    """
    lay = model.state
    lengths = model.rod_lengths()
    s = np.zeros(lay.size)
    q = np.zeros(lay.size)
    g = 0
    for t in model.tethers:
        span = slice(g, g + t.rods)
        whole = float(np.sum(lengths[span])) / (2 * SQ3)
        for r in range(g, g + t.rods):
            q[lay.rod(r)] = whole
        g += t.rods
    s[lay.q] = q[lay.q]
    s[lay.qd] = q[lay.q] / ref_time_s
    return s
