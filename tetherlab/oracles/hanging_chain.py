"""The hanging chain with a tip mass in uniform gravity: lateral modes of the continuum and of a
chain of rigid uniform bars (docs/hanging-chain.md).

Independent of the simulator: it imports nothing of tetherlab (no rod, chain or kernel code);
plain scipy Bessel functions, a bracketed root finder and a dense generalized eigenproblem.

* :func:`continuum_frequencies`: the inextensible heavy chain (mass per length rho, length l)
  with a point mass m_tip at its free end, hanging from a fixed point: its lateral modes are
  Y(xi) = A J0(z) + B Y0(z), z = 2 omega sqrt(xi / g), xi = x + m_tip / rho with x the height
  above the tip; the frequencies solve the 2x2 determinant of the top (Y = 0) and tip
  (m_tip Y'' = T Y') conditions (docs/hanging-chain.md section 1, eq. H5).
* :func:`continuum_mode`: the mode shape, lateral displacement against height above the tip.
* :func:`chain_matrices`, :func:`chain_modes`: the rigid-link chain of n uniform bars (lengths
  l_j, masses m_j, centroidal inertia m_j l_j^2 / 12) and the tip mass, linearised about the
  vertical: M theta'' + K theta = 0 with theta_j the bar angles from the vertical
  (docs/hanging-chain.md section 2, eqs. H8-H9); eigenvalues omega^2 of (K, M).

| parameter | unit | meaning |
|-----------|------|---------|
| length_m | m | chain length (inextensible) |
| mass_kg | kg | chain mass (uniform) |
| tip_mass_kg | kg | point mass at the free end (>= 0) |
| g_m_s2 | m/s2 | gravity |
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import brentq
from scipy.special import j0, j1, y0, y1


def _check(length_m, mass_kg, tip_mass_kg, g_m_s2):
    for key, value, low in (("length_m", length_m, 0.0), ("mass_kg", mass_kg, 0.0), ("g_m_s2", g_m_s2, 0.0)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > low):
            raise ValueError(f"{key}: expected a finite number > {low}, got {value!r}")
    if not (isinstance(tip_mass_kg, (int, float)) and math.isfinite(tip_mass_kg) and tip_mass_kg >= 0.0):
        raise ValueError(f"tip_mass_kg: expected a finite number >= 0, got {tip_mass_kg!r}")


def _determinant(omega, length_m, a_m, g):
    """det of the top and tip conditions for Y = A J0(z) + B Y0(z) (eq. H5), scaled to O(1)."""
    z_top = 2.0 * omega * math.sqrt((length_m + a_m) / g)
    if a_m == 0.0:  # no tip mass: Y0 is singular at the free end, B = 0, J0(z_top) = 0
        return j0(z_top)
    z_a = 2.0 * omega * math.sqrt(a_m / g)
    # tip: Y_z(z_a) = -(z_a / 2) Y(z_a), with J0' = -J1, Y0' = -Y1
    tip_j = -j1(z_a) + 0.5 * z_a * j0(z_a)
    tip_y = -y1(z_a) + 0.5 * z_a * y0(z_a)
    return j0(z_top) * tip_y - y0(z_top) * tip_j


def continuum_frequencies(length_m, mass_kg, tip_mass_kg, g_m_s2, count: int = 2) -> np.ndarray:
    """The first ``count`` lateral angular frequencies (rad/s) of the hanging chain with a tip mass.

    Roots of the determinant (eq. H5) bracketed on a fine grid in omega and refined by Brent's
    method to 1e-15 relative; each bracket is a sign change (the determinant is continuous in
    omega > 0 and its roots are simple)."""
    _check(length_m, mass_kg, tip_mass_kg, g_m_s2)
    rho = mass_kg / length_m
    a_m = tip_mass_kg / rho
    w_scale = math.sqrt(g_m_s2 / length_m)
    grid = np.linspace(1e-3, 20.0 * (count + 1), 4000 * (count + 1)) * w_scale
    vals = np.array([_determinant(w, length_m, a_m, g_m_s2) for w in grid])
    roots = []
    for k in range(grid.size - 1):
        if vals[k] == 0.0 or vals[k] * vals[k + 1] < 0.0:
            roots.append(brentq(_determinant, grid[k], grid[k + 1], args=(length_m, a_m, g_m_s2), xtol=1e-300, rtol=1e-15))
            if len(roots) == count:
                return np.array(roots)
    raise ValueError(f"count: found only {len(roots)} frequencies below {grid[-1]:.4g} rad/s, asked for {count}")


def continuum_mode(omega_rad_s, height_m, length_m, mass_kg, tip_mass_kg, g_m_s2) -> np.ndarray:
    """Lateral displacement of the mode of ``omega_rad_s`` at ``height_m`` above the tip
    (0 at the tip, ``length_m`` at the support), normalised to 1 at the tip."""
    _check(length_m, mass_kg, tip_mass_kg, g_m_s2)
    x = np.asarray(height_m, float)
    rho = mass_kg / length_m
    a_m = tip_mass_kg / rho
    z = 2.0 * omega_rad_s * np.sqrt((x + a_m) / g_m_s2)
    z_top = 2.0 * omega_rad_s * math.sqrt((length_m + a_m) / g_m_s2)
    if a_m == 0.0:
        shape = j0(z)
    else:  # A J0 + B Y0 with the top condition A J0(z_top) + B Y0(z_top) = 0
        shape = y0(z_top) * j0(z) - j0(z_top) * y0(z)
    z_a = 2.0 * omega_rad_s * math.sqrt(a_m / g_m_s2)
    tip = j0(z_a) if a_m == 0.0 else y0(z_top) * j0(z_a) - j0(z_top) * y0(z_a)
    return shape / tip


def chain_matrices(lengths_m, masses_kg, tip_mass_kg, g_m_s2) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the rigid-link chain linearised about the vertical (eqs. H8-H9).

    Bar j (1 at the support) has length l_j, mass m_j and centroidal inertia m_j l_j^2 / 12; its
    centre moves laterally by x_j = sum_{i<j} l_i theta_i + l_j theta_j / 2 and the tip by
    sum_i l_i theta_i, so M = sum_j m_j c_j c_j^T + diag(m_j l_j^2 / 12) + m_tip l l^T with
    c_j = (l_1, ..., l_{j-1}, l_j / 2, 0, ...); the potential g sum (weights below the joint)
    (1 - cos theta_j) l_j gives K = diag(g l_j (m_j / 2 + sum_{i>j} m_i + m_tip))."""
    lengths = np.asarray(lengths_m, float)
    masses = np.asarray(masses_kg, float)
    if lengths.ndim != 1 or lengths.shape != masses.shape or lengths.size == 0:
        raise ValueError(f"lengths_m, masses_kg: expected two 1-D arrays of the same size, got {lengths.shape}, {masses.shape}")
    if not (np.all(lengths > 0) and np.all(masses > 0)):
        raise ValueError("lengths_m, masses_kg: expected every bar with a positive length and mass")
    n = lengths.size
    c = np.tril(np.ones((n, n)), -1) * lengths[None, :] + np.diag(0.5 * lengths)  # row j: c_j
    mass_matrix = (c.T * masses) @ c + np.diag(masses * lengths**2 / 12.0) + tip_mass_kg * np.outer(lengths, lengths)
    below = np.concatenate([np.cumsum(masses[::-1])[::-1][1:], [0.0]])  # sum_{i>j} m_i
    stiffness = np.diag(g_m_s2 * lengths * (0.5 * masses + below + tip_mass_kg))
    return mass_matrix, stiffness


def chain_modes(lengths_m, masses_kg, tip_mass_kg, g_m_s2) -> tuple[np.ndarray, np.ndarray]:
    """(omega (n,), modes (n, n)) of the rigid-link chain: angular frequencies ascending and the
    bar angles of each mode in its column, scaled so the tip moves by 1 m (sum_j l_j theta_j = 1) where it moves at all."""
    mass_matrix, stiffness = chain_matrices(lengths_m, masses_kg, tip_mass_kg, g_m_s2)
    w2, vecs = eigh(stiffness, mass_matrix)
    lengths = np.asarray(lengths_m, float)
    tip = lengths @ vecs
    # a mode whose tip stays put (to round-off) keeps eigh's scaling instead
    scale = np.where(np.abs(tip) > 1e-12 * np.abs(vecs).max(axis=0) * lengths.sum(), tip, 1.0)
    return np.sqrt(w2), vecs / scale[None, :]


def uniform_chain_modes(n: int, length_m, mass_kg, tip_mass_kg, g_m_s2):
    """:func:`chain_modes` for n equal bars."""
    return chain_modes(np.full(n, length_m / n), np.full(n, mass_kg / n), tip_mass_kg, g_m_s2)
