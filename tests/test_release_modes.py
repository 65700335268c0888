"""The mode start's slowest lateral modes by Lanczos on the O(n) mass-matrix product
(initial/release.py, docs/inextensible.md section 7) against the dense pencil they replace."""

import numpy as np
import pytest

from tetherlab.initial import release
from tetherlab.initial.release import _mass_product, lateral_modes

G = 9.80665


def _chain(n, uniform):
    """A 10 m, 1 kg chain with a 0.5 kg end mass (studies/scenes/hanging-chain.toml), in equal rods
    or in rods of lengths and masses drawn within +-50 % of equal (a seeded draw)."""
    if uniform:
        return np.full(n, 10.0 / n), np.full(n, 1.0 / n)
    rng = np.random.default_rng(n)
    return rng.uniform(0.5, 1.5, n) * 10.0 / n, rng.uniform(0.5, 1.5, n) * 1.0 / n


@pytest.mark.parametrize("uniform", [True, False])
@pytest.mark.parametrize("n", [4, 5, 8, 16, 32, 64])
def test_slowest_modes_agree_with_dense_pencil(n, uniform, monkeypatch):
    monkeypatch.setattr(release, "DENSE_UP_TO", 0)  # Lanczos at every n, the dense pencil below
    # Expected: scipy.linalg.eigh on the dense pencil (the route before), whose own rounding is
    # ~eps cond(M) relative in omega^2 (residual 1.6e-12 at 64 rods against Lanczos' 6e-16; 1.07e-12
    # in omega at 64 rods on one machine, below 1e-12 on another): the bound is eps cond(M), at
    # least 1e-12, with cond(M) of the pencil at hand.
    lengths, masses = _chain(n, uniform)
    w_all, t_all = lateral_modes(lengths, masses, 0.5, G)
    lever = np.tril(np.ones((n, n)), -1) * lengths[None, :] + np.diag(0.5 * lengths)
    dense = (lever.T * masses) @ lever + np.diag(masses * lengths**2 / 12.0) + 0.5 * np.outer(lengths, lengths)
    tol = max(1e-12, np.finfo(float).eps * np.linalg.cond(dense))
    for count in (1, 2, 3):
        w, t = lateral_modes(lengths, masses, 0.5, G, count=count)
        assert w.shape == (count,) and t.shape == (n, count)
        assert np.max(np.abs(w - w_all[:count]) / w_all[:count]) < tol
        assert np.max(np.abs(t - t_all[:, :count])) < tol * np.max(np.abs(t_all[:, :count]))
        # The sign convention: the end mass moves sideways by +1 m.
        assert np.allclose(lengths @ t, 1.0, rtol=1e-13, atol=0.0)


@pytest.mark.parametrize("n", [16, 256])
def test_slowest_mode_solves_the_pencil(n, monkeypatch):
    monkeypatch.setattr(release, "DENSE_UP_TO", 0)
    # K theta = omega^2 M theta with the O(n) product, itself checked against the dense M:
    # the residual at rounding (1e-13 of K theta's size, a few hundred eps).
    lengths, masses = _chain(n, False)
    lever = np.tril(np.ones((n, n)), -1) * lengths[None, :] + np.diag(0.5 * lengths)
    dense = (lever.T * masses) @ lever + np.diag(masses * lengths**2 / 12.0) + 0.5 * np.outer(lengths, lengths)
    x = np.random.default_rng(0).standard_normal(n)
    assert np.max(np.abs(_mass_product(lengths, masses, 0.5, x) - dense @ x)) < 1e-13 * np.max(np.abs(dense @ x))
    below = np.concatenate([np.cumsum(masses[::-1])[::-1][1:], [0.0]])
    stiff = G * lengths * (0.5 * masses + below + 0.5)
    w, t = lateral_modes(lengths, masses, 0.5, G, count=2)
    for k in range(2):
        r = stiff * t[:, k] - w[k] ** 2 * _mass_product(lengths, masses, 0.5, t[:, k])
        assert np.max(np.abs(r)) < 1e-13 * np.max(np.abs(stiff * t[:, k]))
    assert w[0] < w[1]


def test_shipped_sizes_keep_the_dense_route(monkeypatch):
    # At DENSE_UP_TO rods and below the start is the dense pencil's: Lanczos is never called, and
    # the modes are the full pencil's first two. Not compared as bits: the same eigh call on the
    # same matrix returned eigenvectors differing in the last bits between two calls on one machine
    # (its LAPACK's blocked kernels), so to eps cond(M) as above.
    def lanczos(*args, **kwargs):
        raise AssertionError("the Lanczos route was taken at DENSE_UP_TO rods")

    monkeypatch.setattr(release, "_slowest_modes", lanczos)
    n = release.DENSE_UP_TO
    lengths, masses = _chain(n, True)
    w_all, t_all = lateral_modes(lengths, masses, 0.5, G)
    w, t = lateral_modes(lengths, masses, 0.5, G, count=2)
    lever = np.tril(np.ones((n, n)), -1) * lengths[None, :] + np.diag(0.5 * lengths)
    dense = (lever.T * masses) @ lever + np.diag(masses * lengths**2 / 12.0) + 0.5 * np.outer(lengths, lengths)
    tol = max(1e-12, np.finfo(float).eps * np.linalg.cond(dense))
    assert np.max(np.abs(w - w_all[:2]) / w_all[:2]) < tol
    assert np.max(np.abs(t - t_all[:, :2])) < tol * np.max(np.abs(t_all[:, :2]))
