"""The lumped-mass (bead) tether oracle, alone and against TMED (docs/bead.md).

Expected values and their sources:
* exact continuous tension: tetherlab.oracles.continuum.exact_vertical_tension (docs/bead.md B5),
  itself checked against the closed-form Hill tension (B4) to O(L/r0);
* lateral modes: the continuous string with varying tension (docs/bead.md C1-C3), whose rigid
  root lambda = 3 omega^2 (2 omega libration) is checked exactly;
* libration: rigid tether, sqrt(3) omega pi/(2 K(sin^2 theta0)) (docs/bead.md A2).
The tolerances are the measured discretisation errors of studies/bead_vs_tmed.py (docs/bead.md,
section 7) with a margin of about 2.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest

from tetherlab.oracles import bead as B
from tetherlab.oracles import bead_scene as BS
from tetherlab.oracles import continuum as C
from tetherlab.scene import load_scene

from .helpers import MU_EARTH, ROOT, SCENES

_spec = importlib.util.spec_from_file_location("bead_vs_tmed", ROOT / "studies" / "bead_vs_tmed.py")
study = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(study)

R0 = 7.4e6  # m, circular orbit of the scenes (paper section 4.3)
OMEGA = math.sqrt(MU_EARTH / R0**3)
M0, MF, MT, L, EA = 1000.0, 100.0, 10.0, 5000.0, 5e4  # the scenes' tether (bench-libration.toml)


def test_bead_model_independent_of_tmed_code():
    # The oracle must share no tether code with TMED (an independent path): check the imports in its sources.
    import tetherlab.oracles as pkg

    for path in (ROOT / "tetherlab" / "oracles").glob("*.py"):
        imports = [ln for ln in path.read_text().splitlines() if ln.lstrip().startswith(("import ", "from "))]
        for banned in ("tether.", "..tether", "system", "kernel", "pipeline", "diagnostics", "formulations"):
            assert not any(banned in ln for ln in imports), f"{path.name} imports {banned}"
    assert pkg is not None


def test_node_masses_keep_mass_and_centre_of_mass():
    # Half-segment lumping (docs/bead.md eq. 1): total mass and straight-line centre of mass exact.
    m = B.BeadModel(5, M0, MF, L, MT, EA, 0.0, MU_EARTH)
    w = m.node_masses()
    assert w.sum() == pytest.approx(M0 + MF + MT, rel=1e-15)
    com = w @ m.node_arclength_m() / w.sum()
    assert com == pytest.approx(C.com_offset_m(M0, MF, MT, L), rel=1e-14)


def test_bad_bead_count_is_refused():
    with pytest.raises(ValueError, match="beads: expected an integer >= 1"):
        B.BeadModel(0, M0, MF, L, MT, EA, 0.0, MU_EARTH)


def test_energy_is_conserved_without_damping():
    # Conservative model (springs + point gravity): the energy of a libration run is constant to
    # the integration tolerance (1e-9 of the elastic+kinetic relative motion energy is far above it).
    scene = load_scene(SCENES / "libration-inplane.toml").replace(**{"duration": "0.2 orbits", "output.count": 21})
    bs = BS.bead_from_scene(scene, 4)
    res = B.integrate(bs.model, bs.y0, bs.t_out_s, method="dop853", rtol=1e-12, atol_scaled=1e-12)
    E = B.energy(bs.model, res.y)
    # Scale: the libration energy ~ M omega^2 L^2 (3/2 sin^2 theta0) ~ 1e1 J; the total E ~ -6e10 J.
    assert np.max(np.abs(E - E[0])) < 1e-3  # J


def test_vertical_equilibrium_stays_vertical():
    # Paper section 4.3 / gate vertical_equilibrium for TMED (1e-6 rad over the run): the bead model's own
    # relative equilibrium must stay on the local vertical just as well.
    scene = load_scene(SCENES / "vertical-equilibrium.toml").replace(**{"duration": "1 orbits", "output.count": 51})
    bs = BS.bead_from_scene(scene, 3)
    res = B.integrate(bs.model, bs.y0, bs.t_out_s, method="radau5", rtol=1e-11, atol_scaled=1e-11)
    th, ph = B.libration_angles(bs.model, res.y, bs.side)
    assert np.max(np.abs(th)) < 1e-6 and np.max(np.abs(ph)) < 1e-6


def test_exact_tension_agrees_with_hill_to_order_L_over_r():
    # B4 (Hill) and B5 (exact) differ by O(L/r0) = 6.8e-4 (docs/bead.md section 5).
    ex = C.exact_vertical_tension(M0, MF, MT, L, EA, MU_EARTH, R0)
    hill = C.hill_vertical_tension(M0, MF, MT, L, OMEGA)
    assert ex.tension_root_N == pytest.approx(hill[0], rel=L / R0)
    assert ex.tension_tip_N == pytest.approx(hill[1], rel=L / R0)
    # The root's and tip's tensions differ by the tether's own gravity gradient, ~ 3 omega^2 m_t (L/2 - a)
    assert ex.tension_root_N - ex.tension_tip_N == pytest.approx(3 * OMEGA**2 * MT * (L / 2 - C.com_offset_m(M0, MF, MT, L)), rel=0.01)


@pytest.mark.parametrize("n", [1, 4])
def test_bead_attachment_tension_converges_to_exact(n):
    # Measured (docs/bead.md section 7): root error 2.6e-6 (n=1), 4.1e-7 (n=4); tolerance x2.
    ref = C.exact_vertical_tension(M0, MF, MT, L, EA, MU_EARTH, R0)
    t_root, t_tip = study.tension_bead(n)
    tol = {1: 6e-6, 4: 1e-6}[n]
    assert t_root == pytest.approx(ref.tension_root_N, rel=tol)
    assert t_tip == pytest.approx(ref.tension_tip_N, rel=tol)


def test_tmed_and_bead_tension_agree():
    # Two rods / four beads against each other and the exact value (docs/bead.md section 7:
    # TMED n=2 3.3e-8, bead n=4 4.1e-7).
    ref = C.exact_vertical_tension(M0, MF, MT, L, EA, MU_EARTH, R0)
    tm = study.tension_tmed(2)
    bd = study.tension_bead(4)
    assert tm[0] == pytest.approx(ref.tension_root_N, rel=1e-7)
    assert bd[0] == pytest.approx(tm[0], rel=1e-6)
    assert bd[1] == pytest.approx(tm[1], rel=1e-6)


def test_string_modes_have_rigid_root_and_uniform_limit():
    # lambda = 3 omega^2 solves C1-C3 exactly with Z = x (rigid out-of-plane libration at 2 omega):
    rho = MT / L
    tension = lambda s: float(C.hill_tension_profile(s, M0, MF, MT, L, OMEGA))  # noqa: E731
    resid, _ = C._oop_shoot(3 * OMEGA**2, M0, MF, rho, L, tension)
    assert abs(resid) < 1e-9 * M0 * 3 * OMEGA**2 * L  # N, relative to the root's tidal force
    modes = C.out_of_plane_modes(M0, MF, MT, L, OMEGA, 2)
    # With end masses 10-100 x the tether's, the string is close to fixed-fixed: within 2 % of
    # the uniform string at the mean tension (textbook f_k = k/(2L) sqrt(T/rho)).
    t_mean = float(np.mean(C.hill_tension_profile(np.linspace(0, L, 1001), M0, MF, MT, L, OMEGA)))
    for k, mode in enumerate(modes, start=1):
        uni = C.uniform_string_frequency(k, L, t_mean, rho)
        assert mode.omega_rad_s == pytest.approx(math.sqrt(uni**2 + OMEGA**2), rel=0.02)


def test_fit_frequencies_recovers_a_known_signal():
    t = np.linspace(0, 5000, 4001)
    q = 0.3 * np.cos(0.0123 * t + 0.4) + 1.0 * np.sin(0.002 * t) + 0.01
    w, amps, rms = C.fit_frequencies(t, q, [0.0021, C.spectral_peak(t, q, 0.01, 0.02)])
    assert w[1] == pytest.approx(0.0123, rel=1e-9)
    assert amps[1] == pytest.approx(0.3, rel=1e-7)


def test_libration_bead_and_tmed_agree_small_n():
    # Rigid in-plane libration (docs/bead.md A2): both models within 0.1 % of sqrt3 omega x the
    # elliptic correction (the 0.2 % libration gate halved), and within 1e-5 of each other.
    ref = study.libration_reference(2.0)
    tm = study.libration_tmed(2, 2.0)
    bd = study.libration_bead(2, 2.0)
    assert tm == pytest.approx(ref, rel=1e-3)
    assert bd == pytest.approx(ref, rel=1e-3)
    assert bd == pytest.approx(tm, rel=1e-5)


def test_first_lateral_mode_small_n():
    # Measured (docs/bead.md section 7): n = 4, TMED +2.6 %, bead -1.7 % from the continuous
    # string; a beaded string is low by about (pi/(N+1))^2/24 (Rayleigh 1894, sec. 120).
    ref = study.lateral_references(1)["continuum"]
    tm = study.lateral_tmed(4, 1)
    bd = study.lateral_bead(4, 1)
    assert 0.0 < tm / ref - 1.0 < 0.05
    assert -0.035 < bd / ref - 1.0 < 0.0


@pytest.mark.slow
def test_full_sweep_converges(tmp_path):
    df, tref, lat, lib = study.run_sweep((8, 16, 32), log=lambda *_: None)
    study.write_report(df, tref, lat, lib, tmp_path)
    for q, tol in (("libration_inplane", 1e-5), ("tension_root", 2e-7), ("lateral_oop_1", 2e-3), ("lateral_oop_2", 6e-3)):
        g = df[(df.quantity == q) & (df.n == 32)]
        v = dict(zip(g.model, g.value))
        if not math.isnan(v["tmed"]):
            assert v["bead"] == pytest.approx(v["tmed"], rel=tol), q  # the two models meet at n = 32
    for q in ("lateral_oop_1", "lateral_oop_2"):
        g = df[(df.quantity == q) & (df.n == 32)]
        assert np.all(np.abs(g.rel_err) < 5e-3), q  # and both are within 0.5 % of the continuum
    assert (tmp_path / "bead_vs_tmed.png").is_file()
