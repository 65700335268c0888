"""The hanging chain's lateral modes by the linearised small-oscillation eigenproblem of each
discrete model about its static hang, against the Bessel solution: the table n = 4 ... 256, both
tether models, modes 1 and 2, and the gates on its observed order and its n = 64 error
(docs/hanging-chain.md sections 5-7).

The eigen-route: the hang (the release's statics, rods turned back to the vertical, lengths with
no axial acceleration), then the Jacobian of the compiled accelerations (tether/solve.py, the
kernel every run integrates) with respect to the rods' sideways components, by central
differences of rotations that keep each rod's length; the lowest eigenvalues of -J are w^2.
About the vertical hang the sideways and axial motions decouple by symmetry (axial motion is even
in the sideways displacement), and a rod's length constraint has the gradient D, vertical, so the
sideways components are already the inextensible model's constraint-reduced coordinates.  No time
integration: 256 rods take about a second.

| parameter | unit | meaning |
|-----------|------|---------|
| n | 1 | rod count |
| model | - | the tether model (scene key tethers.main.model): "paper" (elastic) or "inextensible" |
| ea_N | N | EA of the elastic rods (default: the scene's, 1e7 N) |
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from scipy.special import j0, j1, y0, y1

L_M, MASS_KG, TIP_KG, G, EA_N = 10.0, 1.0, 0.5, 9.80665, 1e7  # studies/scenes/hanging-chain.toml
SQ3 = math.sqrt(3.0)
MODELS = ("paper", "inextensible")
NS = (4, 8, 16, 32, 64, 128, 256)
#: the finite-difference rotation of one rod, relative to its half length: the truncation of the
#: central difference is ~140 step^2 of the frequency (measured: 1.4e-4 at 1e-3, 1.4e-8 at 1e-5,
#: 1.4e-10 at 1e-6, 64 inextensible rods), the sideways response has no cancellation (it is exactly
#: 0 at the vertical), so a small step costs no round-off: 1e-8 leaves 3e-12
STEP_REL = 1e-8


def hang_state(n: int, model: str = "paper", ea_N: float | None = None):
    """(model, y, p) of the hanging chain at rest in its static hang: the release's statics with
    a 1e-12 m mode-1 release (initial/release.py), every rod turned back to the vertical, and for
    the elastic rods the lengths with no axial acceleration (consistent_lengths)."""
    from ..initial.release import consistent_lengths
    from ..pipeline import prepare
    from .inextensible import chain_scene

    prep = prepare(chain_scene(n, model=model, amplitude_m=1e-12, ea=ea_N))
    m = prep.model
    lay = m.state
    p = m.fresh_params()
    y = prep.y0.copy()
    d = y[lay.rods_d].reshape(n, 3)
    r = np.linalg.norm(d, axis=1)
    d[:] = 0.0
    d[:, 2] = -r  # gravity along -z (the scene's uniform_gravity)
    y[lay.rods_d] = d.ravel()
    y[lay.qd] = 0.0
    if model != "inextensible":
        y, _ = consistent_lengths(m, y, p)
    return m, y, p


def lateral_jacobian(m, y, p, step_rel: float = STEP_REL) -> np.ndarray:
    """J[i, j] = d(d''_x of rod i) / d(d_x of rod j) at the hang (1/s^2), by central differences
    of rotations in the x-z plane that keep rod j's length."""
    from ..tether.solve import accelerations

    lay = m.state
    n = lay.n_rods
    q0 = y[lay.q].copy()
    qd = np.zeros(lay.n_qt)
    acc = np.zeros(lay.n_qt)
    r = np.linalg.norm(q0[lay.rods_d].reshape(n, 3), axis=1)
    jac = np.empty((n, n))
    for j in range(n):
        h = step_rel * r[j]
        cols = []
        for s in (h, -h):
            q = q0.copy()
            d = q[lay.rods_d].reshape(n, 3)
            d[j, 0] = s
            d[j, 2] = -math.sqrt(r[j] ** 2 - s * s)
            code = accelerations(0.0, q, qd, p, acc)
            if code != 0:
                raise RuntimeError(f"hanging chain, n = {n}: the accelerations failed (code {code}) with rod {j + 1} turned")
            cols.append(acc[lay.rods_d].reshape(n, 3)[:, 0].copy())
        jac[:, j] = (cols[0] - cols[1]) / (2.0 * h)
    return jac


def lateral_frequencies(n: int, model: str = "paper", count: int = 2, ea_N: float | None = None) -> np.ndarray:
    """The ``count`` lowest lateral angular frequencies (rad/s) of the discrete model about its hang."""
    return frequencies_and_lengths(n, model, count, ea_N)[0]


def frequencies_and_lengths(n: int, model: str = "paper", count: int = 2, ea_N: float | None = None):
    """(the ``count`` lowest lateral angular frequencies (rad/s), the rods' lengths in the hang (m))."""
    from scipy.sparse.linalg import eigs

    m, y, p = hang_state(n, model, ea_N)
    a = -lateral_jacobian(m, y, p)
    if n <= count + 1:  # too small for ARPACK: all of them
        w2 = np.sort(np.linalg.eigvals(a).real)
    else:
        # shift-invert about 0: the lowest eigenvalues to round-off relative to themselves, where a
        # dense QR gets them to round-off relative to the largest (3e-11 of w1^2 at 256 rods); a
        # fixed start vector keeps the result deterministic
        w2 = np.sort(eigs(a, k=count, sigma=0.0, which="LM", v0=np.ones(n), return_eigenvectors=False).real)
    if not w2[0] > 0.0:
        raise RuntimeError(f"hanging chain, n = {n}, model {model}: the hang is not stable (lowest w^2 = {w2[0]:.3g})")
    return np.sqrt(w2[:count]), 2.0 * SQ3 * np.linalg.norm(y[m.state.rods_d].reshape(n, 3), axis=1)


# -- the continuum's quantities (docs/hanging-chain.md 6, 7) ------------------------------------------
def _mode_derivatives(omega: float):
    """(Y', Y'') of the Bessel mode of ``omega`` against the height x above the tip (any scale),
    from Y = A J0(z) + B Y0(z), z = 2 omega sqrt(xi / g), xi = x + a (eq. H3)."""
    rho = MASS_KG / L_M
    a = TIP_KG / rho
    z_top = 2.0 * omega * math.sqrt((L_M + a) / G)
    A, B = y0(z_top), -j0(z_top)

    def dy(x):
        xi = x + a
        z = 2.0 * omega * math.sqrt(xi / G)
        return -(A * j1(z) + B * y1(z)) * omega / math.sqrt(G * xi)  # dY/dz dz/dxi, J0' = -J1

    def ddy(x):
        xi = x + a
        z = 2.0 * omega * math.sqrt(xi / G)
        yv = A * j0(z) + B * y0(z)
        return -(omega**2 * yv / G + dy(x)) / xi  # g (xi Y')' + w^2 Y = 0

    return dy, ddy


def _tension(x):
    return G * (TIP_KG + MASS_KG / L_M * x)  # eq. H1


def leading_coefficient(omega: float) -> float:
    """c in w_n / w - 1 = c / n^2 + O(n^-4) for n equal bars: the bars are the piecewise-linear
    Rayleigh-Ritz (consistent-mass) discretisation of the continuum, whose eigenvalue error is the
    interpolant's energy, (h^2 / 12) int T Y''^2 dx, over int T Y'^2 dx (docs/hanging-chain.md 7)."""
    dy, ddy = _mode_derivatives(omega)
    num = quad(lambda x: _tension(x) * ddy(x) ** 2, 0.0, L_M, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    den = quad(lambda x: _tension(x) * dy(x) ** 2, 0.0, L_M, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    return L_M**2 / 24.0 * num / den


def stretch_offset(omega: float, ea_N: float = EA_N) -> float:
    """w_elastic / w_inextensible - 1 of the continuum to first order in 1/EA: the Rayleigh
    quotient with the sideways stiffness T / (1 + T/EA) per unstretched length,
    -(1/2) int T^2 Y'^2 / EA dx / int T Y'^2 dx (docs/hanging-chain.md 6)."""
    dy, _ = _mode_derivatives(omega)
    num = quad(lambda x: _tension(x) ** 2 * dy(x) ** 2, 0.0, L_M, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    den = quad(lambda x: _tension(x) * dy(x) ** 2, 0.0, L_M, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    return -0.5 * num / (ea_N * den)


def observed_orders(ns, errors) -> np.ndarray:
    """log2 of successive error ratios (rod counts doubling): p between n and 2n."""
    e = np.abs(np.asarray(errors, float))
    return np.log(e[:-1] / e[1:]) / np.log(np.asarray(ns[1:], float) / np.asarray(ns[:-1], float))


def convergence_table(ns=NS, models=MODELS) -> list[dict]:
    """One row per (model, mode, n): the frequency, its error against Bessel (the elastic one with
    the continuum's stretch offset removed), error n^2 against the derived coefficient, and the
    observed order from the previous n."""
    from ..oracles.hanging_chain import continuum_frequencies

    wc = continuum_frequencies(L_M, MASS_KG, TIP_KG, G, count=2)
    coef = [leading_coefficient(w) for w in wc]
    offset = [stretch_offset(w) for w in wc]
    rows = []
    for model in models:
        ws = np.array([lateral_frequencies(n, model) for n in ns])
        for k in range(2):
            raw = ws[:, k] / wc[k] - 1.0
            err = raw - (offset[k] if model != "inextensible" else 0.0)
            orders = np.concatenate([[math.nan], observed_orders(ns, err)])
            for i, n in enumerate(ns):
                rows.append({"model": model, "mode": k + 1, "n": n, "omega_rad_s": float(ws[i, k]),
                             "w/w_Bessel - 1": float(raw[i]), "error": float(err[i]),
                             "error n^2": float(err[i] * n * n), "derived c": coef[k], "order": float(orders[i])})  # fmt: skip
    return rows


#: the gates' rod counts: the order between the last two, the coefficient at ORDER_NS[0]
ORDER_NS = (64, 128, 256)


def check_hanging_chain_modes(rows_out, ns=NS, models=MODELS) -> dict:
    """hanging_chain_bessel_order: max |p - 2| of the observed order between n = 128 and 256;
    hanging_chain_bessel_n64: max |e(64) 64^2 / c - 1|, c the derived leading coefficient; over
    modes 1 and 2 and both models (references/gates.toml).  ``ns``: the table's rod counts (they
    must hold ORDER_NS)."""
    if list(ns) != sorted(ns) or tuple(ns[-2:]) != ORDER_NS[1:] or ORDER_NS[0] not in ns:
        raise ValueError(f"ns: expected ascending rod counts holding {ORDER_NS}, got {ns}")
    rows = convergence_table(ns, models)
    dev_p = dev_c = 0.0
    for r in rows:
        rows_out.append({"case": f"{r['model']}, mode {r['mode']}, n = {r['n']} (eigen-route)", "w (rad/s)": r["omega_rad_s"],
                         "w/w_Bessel - 1": r["w/w_Bessel - 1"], "error (stretch offset removed)": r["error"],
                         "error n^2 / c - 1": r["error n^2"] / r["derived c"] - 1.0, "order from n/2": r["order"]})  # fmt: skip
        if r["n"] == ORDER_NS[-1]:  # the order from ORDER_NS[1]: ns double up to it
            dev_p = max(dev_p, abs(r["order"] - 2.0)) if math.isfinite(r["order"]) else math.inf
        if r["n"] == ORDER_NS[0]:
            dev_c = max(dev_c, abs(r["error n^2"] / r["derived c"] - 1.0))
    return {"hanging_chain_bessel_order": dev_p, "hanging_chain_bessel_n64": dev_c}


def figures(out) -> list:
    """[("hanging-chain", [the figure's path relative to ``out``])]: the table n = 4 ... 256 drawn
    (verify's figures task; the report shows it in the hanging-chain-bessel section)."""
    from pathlib import Path

    path = Path(out) / "hanging_chain_bessel.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    figure(convergence_table(), path)
    return [("hanging-chain", [path.relative_to(out)])]


def figure(rows, path) -> None:
    """Error against n, log-log, both models and modes, with the derived c / n^2 lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for mode, color in ((1, "C0"), (2, "C1")):
        el = [r for r in rows if r["model"] == "paper" and r["mode"] == mode]
        inx = [r for r in rows if r["model"] == "inextensible" and r["mode"] == mode]
        n = np.array([r["n"] for r in el], float)
        ax.loglog(n, el[0]["derived c"] / n**2, "-", color=color, lw=0.8, label=f"c / n$^2$, mode {mode} (derived)")
        ax.loglog(n, np.abs([r["error"] for r in el]), "o", color=color, mfc="none", ms=9,
                  label=f"elastic, mode {mode}, stretch offset removed")
        ax.loglog([r["n"] for r in inx], np.abs([r["error"] for r in inx]), "s", color=color, ms=4,
                  label=f"inextensible, mode {mode}")
        ax.loglog(n, np.abs([r["w/w_Bessel - 1"] for r in el]), "x", color=color, ms=6,
                  label=f"elastic, mode {mode}, as computed (with the offset)")
    ax.set_xlabel("rods n")
    ax.set_ylabel("|w / w_Bessel - 1|")
    ax.set_title("Hanging chain with a tip mass: lateral modes, eigen-route")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
