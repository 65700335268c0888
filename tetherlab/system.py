"""From validated SI values to the compiled model: the parameter block, the state layout, the
initial state and the per-component tolerance scales.

This is the only place that knows both the boundary objects and the kernel layout
(``tetherlab/kernel/layout.py``).  Nothing here is called per right-hand-side evaluation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .forces.registry import EffectSpec
from .kernel import layout as L

SQ3 = np.sqrt(3.0)

#: Strain at which a rod counts as collapsed and the run stops with an error: at eps = -1 the rod
#: has zero length and its direction u is undefined (eq. 8), so the model itself breaks down well
#: before.  -0.9 leaves room for legitimate compression of a slack-free elastic tether.
MIN_STRAIN = -0.9


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

    @property
    def n_rods(self) -> int:
        return int(self.p[L.H_NRODS])

    @property
    def n_state(self) -> int:
        return int(self.p[L.H_NSTATE])

    def fresh_params(self) -> np.ndarray:
        """A copy of the parameter block (the kernel writes scratch and counters into it)."""
        return self.p.copy()

    def rod_masses(self) -> np.ndarray:
        off = int(self.p[L.H_OFF_ROD])
        return self.p[off + L.RT_M : off + self.n_rods * L.RT_SIZE : L.RT_SIZE].copy()

    def rod_lengths(self) -> np.ndarray:
        off = int(self.p[L.H_OFF_ROD])
        return self.p[off + L.RT_LU : off + self.n_rods * L.RT_SIZE : L.RT_SIZE].copy()

    def total_mass(self) -> float:
        return (0.0 if self.root_fixed else self.root_mass_kg) + sum(
            t.mass_kg + t.tip_mass_kg for t in self.tethers
        )


def gauss_legendre_halves(nq: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes xi and weights for the two half rods [-1, 0] and [0, 1]; each half's weights sum to 1."""
    x, w = np.polynomial.legendre.leggauss(nq)
    right = 0.5 * (1.0 + x)
    wr = 0.5 * w
    nodes = np.concatenate([-right[::-1], right])
    weights = np.concatenate([wr[::-1], wr])
    return nodes, weights


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
) -> Model:
    """Pack the parameter block.  Inputs are SI floats that the scene layer has validated.

    ``epoch`` (ISO date, TDB) and ``duration_s`` are for time-dependent effects (ephemerides fitted
    over the run); effects that do not need them ignore them.
    """
    nteth = len(tethers)
    nrods = sum(t.rods for t in tethers)
    n_state = 6 * (1 + nrods)

    # What an effect with per-body or per-tether parameters needs to lay them out in kernel order:
    # body index 0 is the root, 1 + k the tip of tether k (the ``body`` argument of body_force).
    ctx = {
        "bodies": [root_name] + [t.tip_name for t in tethers],
        "tethers": list(tethers),
        "root_fixed": root_fixed,
        "epoch": epoch,
        "duration_s": duration_s,
        "meta": {},  # effects put what the result's meta should report here (by effect name)
    }
    eff_params: list[list[float]] = [
        list(spec.pack(params, central, ctx)) if spec.pack else [] for spec, params in effects
    ]
    sizes = {
        "eff": len(effects) * L.ET_SIZE + sum(len(x) for x in eff_params),
        "teth": nteth * L.TT_SIZE,
        "rod": nrods * L.RT_SIZE,
        "quad": 4 * quadrature,
        "cnt": L.N_EFFECT_CODES,
        # rod scratch, joint scratch (n+1 joints per tether), root 3x3 system (A, b, A^-1)
        "scr": nrods * L.SR_SIZE + (nrods + nteth) * L.SJ_SIZE + 21,
    }
    offs = {}
    pos = L.H_SIZE
    for key in ("eff", "teth", "rod", "quad", "cnt", "scr"):
        offs[key] = pos
        pos += sizes[key]
    p = np.zeros(pos)
    p[L.H_LEN] = pos
    p[L.H_NSTATE] = n_state
    p[L.H_FORM] = L.FORM_COWELL
    p[L.H_NRODS] = nrods
    p[L.H_NTETH] = nteth
    p[L.H_ROOT_INV_M] = 0.0 if root_fixed else 1.0 / root_mass_kg
    p[L.H_ROOT_M] = 0.0 if root_fixed else root_mass_kg
    p[L.H_NEFF] = len(effects)
    p[L.H_OFF_EFF] = offs["eff"]
    p[L.H_OFF_TETH] = offs["teth"]
    p[L.H_OFF_ROD] = offs["rod"]
    p[L.H_OFF_QUAD] = offs["quad"]
    p[L.H_NQ] = quadrature
    p[L.H_OFF_SCR] = offs["scr"]
    p[L.H_OFF_CNT] = offs["cnt"]
    p[L.H_FAIL_ROD] = -1
    p[L.H_MIN_STRAIN] = MIN_STRAIN

    # effect table, parameters after the table
    par = offs["eff"] + len(effects) * L.ET_SIZE
    for e, ((spec, _), vals) in enumerate(zip(effects, eff_params)):
        base = offs["eff"] + e * L.ET_SIZE
        p[base + L.ET_CODE] = spec.code
        p[base + L.ET_OFF_PAR] = par
        p[base + L.ET_NPAR] = len(vals)
        p[par : par + len(vals)] = vals
        par += len(vals)

    rod_slices = []
    g = 0
    for k, t in enumerate(tethers):
        base = offs["teth"] + k * L.TT_SIZE
        p[base + L.TT_NRODS] = t.rods
        p[base + L.TT_ROD0] = g
        p[base + L.TT_TIP_INV_M] = 1.0 / t.tip_mass_kg if t.tip_mass_kg > 0 else 0.0
        p[base + L.TT_TIP_M] = t.tip_mass_kg
        p[base + L.TT_MODEL] = {"paper": L.MODEL_PAPER, "energy": L.MODEL_ENERGY, "printed": L.MODEL_PRINTED}[t.model]
        rod_slices.append(slice(g, g + t.rods))
        for _ in range(t.rods):
            rb = offs["rod"] + g * L.RT_SIZE
            # equal rods: each has L_u/n and m_t/n (paper section 2.2 allows any split)
            p[rb + L.RT_M] = t.mass_kg / t.rods
            p[rb + L.RT_LU] = t.length_m / t.rods
            p[rb + L.RT_EA] = t.ea_n
            p[rb + L.RT_D] = t.damping_n_s
            p[rb + L.RT_TETH] = k
            g += 1

    nodes, weights = gauss_legendre_halves(quadrature)
    p[offs["quad"] : offs["quad"] + 2 * quadrature] = nodes
    p[offs["quad"] + 2 * quadrature : offs["quad"] + 4 * quadrature] = weights

    return Model(
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
    )


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
    with angular velocity ``omega`` (None: pure translation), so d_i' = omega x d_i.
    """
    nrods = model.n_rods
    q = np.zeros(3 * (1 + nrods))
    qd = np.zeros_like(q)
    q[:3] = r0
    qd[:3] = v0
    lengths = model.rod_lengths()
    w = np.zeros(3) if omega is None else np.asarray(omega, float)
    for k, _ in enumerate(model.tethers):
        sl = model.rod_slices[k]
        dirs = np.asarray(rod_dirs[k], float)
        for j, g in enumerate(range(sl.start, sl.stop)):
            u = dirs[j] / np.linalg.norm(dirs[j])
            d = u * lengths[g] * (1.0 + strains[k]) / (2.0 * SQ3)  # eq. 3
            q[3 + 3 * g : 6 + 3 * g] = d
            qd[3 + 3 * g : 6 + 3 * g] = np.cross(w, d)
    return np.concatenate([q, qd])


def point_positions(model: Model, y: np.ndarray) -> dict:
    """Inertial positions/velocities of the root, rod centres, joints and tips for one state (eq. 23)."""
    nr = model.n_rods
    h = 3 * (1 + nr)
    q = y[:h]
    qd = y[h:]
    r0 = q[:3]
    v0 = qd[:3]
    d = q[3:].reshape(nr, 3)
    dd = qd[3:].reshape(nr, 3)
    rG = np.zeros((nr, 3))
    vG = np.zeros((nr, 3))
    joints = []  # per tether: (n_k + 1, 3) positions of A_1, B_1, ..., B_n
    jvel = []
    for sl in model.rod_slices:
        a = r0.copy()
        av = v0.copy()
        js = [a.copy()]
        jv = [av.copy()]
        for g in range(sl.start, sl.stop):
            rG[g] = a + SQ3 * d[g]
            vG[g] = av + SQ3 * dd[g]
            a = a + 2 * SQ3 * d[g]
            av = av + 2 * SQ3 * dd[g]
            js.append(a.copy())
            jv.append(av.copy())
        joints.append(np.array(js))
        jvel.append(np.array(jv))
    return {"r0": r0, "v0": v0, "d": d, "dd": dd, "rG": rG, "vG": vG, "joints": joints, "jvel": jvel}


def center_of_mass(model: Model, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    pts = point_positions(model, y)
    m = model.rod_masses()
    M = 0.0
    r = np.zeros(3)
    v = np.zeros(3)
    if not model.root_fixed:
        M += model.root_mass_kg
        r += model.root_mass_kg * pts["r0"]
        v += model.root_mass_kg * pts["v0"]
    M += m.sum()
    r += m @ pts["rG"]
    v += m @ pts["vG"]
    for k, t in enumerate(model.tethers):
        if t.tip_mass_kg > 0:
            M += t.tip_mass_kg
            r += t.tip_mass_kg * pts["joints"][k][-1]
            v += t.tip_mass_kg * pts["jvel"][k][-1]
    return r / M, v / M


def tolerance_scales(model: Model, ref_length_m: float, ref_time_s: float) -> np.ndarray:
    """Natural scale of each state component: atol_i = atol * scale_i (atol in scale units).

    Root position: the orbit radius; root velocity: radius/time unit; d_i: the rod's half
    TMED separation L_u/(2 sqrt 3); d_i': that over the time unit.  So a scene's atol = 1e-10
    means 1e-10 of each quantity's own size, not 1e-10 m on a 7000 km orbit radius.
    """
    nr = model.n_rods
    lengths = model.rod_lengths()
    s_q = np.empty(3 * (1 + nr))
    s_q[:3] = ref_length_m
    for g in range(nr):
        s_q[3 + 3 * g : 6 + 3 * g] = lengths[g] / (2 * SQ3)
    s_v = s_q / ref_time_s
    return np.concatenate([s_q, s_v])
