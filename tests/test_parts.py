"""The part interface: the 3x3 algebra of the kernels (kernel/vec3.py) against numpy, and every
part's energy and momentum share (bodies/point.py, bodies/rigid_body.py with its wheels,
tether/chain.py per rod) summing to the diagnostics' totals."""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab import diagnostics
from tetherlab.kernel import vec3
from tetherlab.kernel.shares import SH_E, SH_SIZE
from tetherlab.pipeline import prepare

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(20)


def test_vectors_against_numpy(rng):
    for _ in range(20):
        a, b = rng.standard_normal(3), rng.standard_normal(3)
        np.testing.assert_allclose(vec3.cross(*a, *b), np.cross(a, b), rtol=0, atol=8 * EPS)
        assert vec3.dot(*a, *b) == pytest.approx(a @ b, rel=0, abs=8 * EPS)
        assert vec3.norm(*a) == pytest.approx(np.linalg.norm(a), rel=4 * EPS)


def test_matrices_against_numpy(rng):
    o = 5  # an offset into a flat block, as the kernels store them
    for _ in range(20):
        A = rng.standard_normal((3, 3)) + 3 * np.eye(3)
        v = rng.standard_normal(3)
        blk = np.zeros(o + 9 + 9)
        blk[o : o + 9] = A.ravel()
        np.testing.assert_allclose(vec3.mat_vec(blk, o, *v), A @ v, rtol=0, atol=32 * EPS)
        np.testing.assert_allclose(vec3.mat_t_vec(blk, o, *v), A.T @ v, rtol=0, atol=32 * EPS)
        det = vec3.inv3(blk, o, blk, o + 9)
        # A = N(0,1) + 3I has a condition number of order 10: a cofactor inverse and numpy's LU
        # each round to a few ulps times that, far inside 1e-12 (and 1e-13 for the determinant)
        assert det == pytest.approx(np.linalg.det(A), rel=1e-13)
        np.testing.assert_allclose(blk[o + 9 :].reshape(3, 3), np.linalg.inv(A), rtol=1e-12, atol=1e-14)
        # in place, as the elimination inverts its diagonal blocks
        vec3.inv3(blk, o, blk, o)
        np.testing.assert_allclose(blk[o : o + 9].reshape(3, 3), np.linalg.inv(A), rtol=1e-12, atol=1e-14)
    assert vec3.inv3(np.zeros(9), 0, np.zeros(9), 0) == 0.0


def test_n_by_n_inverse_and_product_against_numpy(rng):
    n = 6
    A = rng.standard_normal((n, n)) + 4 * np.eye(n)
    x = rng.standard_normal(n)
    a, out, xv, yv = 3, 3 + n * n, 3 + 2 * n * n, 3 + 2 * n * n + n
    p = np.zeros(yv + n)
    p[a : a + n * n] = A.ravel()
    p[xv : xv + n] = x
    det = vec3.inv_n(p, a, out, n)
    assert det == pytest.approx(np.linalg.det(A), rel=1e-12)
    Ai = p[out : out + n * n].reshape(n, n)
    np.testing.assert_allclose(Ai, np.linalg.inv(A), rtol=1e-12, atol=1e-14)
    vec3.mat_vec_n(p, out, xv, yv, n)
    np.testing.assert_allclose(p[yv : yv + n], Ai @ x, rtol=1e-13, atol=1e-15)


def test_rod_block_forms_against_numpy(rng):
    u = rng.standard_normal(3)
    u /= np.linalg.norm(u)
    alpha, beta = 1.7, -0.6
    K = alpha * np.eye(3) + beta * np.outer(u, u)
    v = rng.standard_normal(3)
    np.testing.assert_allclose(vec3.iuu_vec(alpha, beta, *u, *v), K @ v, rtol=0, atol=16 * EPS)
    B = rng.standard_normal((3, 3))
    S = B @ B.T + np.eye(3)  # symmetric, as S^-1 of the elimination
    blk = np.zeros(18)
    blk[:9] = B.ravel()
    vec3.add_iuu(blk, 0, alpha, beta, *u)
    np.testing.assert_allclose(blk[:9].reshape(3, 3), B + K, rtol=0, atol=16 * EPS)
    blk[:9] = B.ravel()
    blk[9:] = S.ravel()
    vec3.sub_iuu_sandwich(blk, 0, 9, alpha, beta, *u)
    np.testing.assert_allclose(blk[:9].reshape(3, 3), B - K @ S @ K, rtol=0, atol=64 * EPS * np.abs(S).max())


def _scenes():
    from tests.test_rigid import chain_scene, rigid_tree_scene, star_both_ways_scene

    return {"chain": chain_scene, "star-both-ways": star_both_ways_scene, "rigid-tree": rigid_tree_scene}


@pytest.mark.parametrize("name", ["chain", "star-both-ways", "rigid-tree"])
def test_part_shares_sum_to_the_diagnostics_totals(name):
    prep = prepare(_scenes()[name]())
    model = prep.model
    y = prep.y0.copy()
    rng = np.random.default_rng(3)
    nqt = model.n_qt
    y[nqt : 2 * nqt] += 1e-3 * rng.standard_normal(nqt)  # stir the velocities: every share non-zero
    t = 12.5
    parts = diagnostics.shares(model, t, y)
    assert parts.shape == (len(model.bodies) + len(model.tethers), SH_SIZE)
    glob = diagnostics.compute(model, np.array([t]), y[None, :])["global"][0]
    total = parts.sum(axis=0)
    total[SH_E] = total[diagnostics.G_KE] + total[diagnostics.G_VG] + total[diagnostics.G_VE]
    scale = np.abs(parts).sum(axis=0)
    scale[SH_E] = scale[diagnostics.G_KE] + scale[diagnostics.G_VG] + scale[diagnostics.G_VE]
    # the same terms added in another grouping: a few roundings of the largest term each
    assert np.all(np.abs(total - glob) <= 64 * EPS * scale), (total - glob) / np.maximum(scale, 1e-300)
    # every part contributes: each body and each tether has mass and moves
    assert np.all(np.abs(parts[:, diagnostics.G_KE]) > 0)
