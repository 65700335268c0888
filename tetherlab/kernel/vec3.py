"""3-vectors and small dense blocks on flat float64 arrays: the algebra of the compiled kernels.

Vectors travel as three scalars and come back as tuples (no allocation); matrices live row-major
in a flat array at an offset (``a[o:o+9]`` for 3x3), as the parameter block stores them.  Every
helper evaluates its expression in one fixed operation order, the order of the unrolled code it
replaced, so a kernel that calls it gives the same bits as before; change an order here only with
the golden check (tests/golden.py) run before and after.

The block form ``alpha I + beta u u^T`` (u a unit vector) is the shape of every matrix of a TMED
rod (docs/model.md 4.3: C, P and M), so it has its own helpers.
"""

from __future__ import annotations

import math

from .._jit import njit


@njit(cache=True, inline="always")
def cross(ax, ay, az, bx, by, bz):
    """a x b."""
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, inline="always")
def dot(ax, ay, az, bx, by, bz):
    """a . b, summed x + y + z."""
    return ax * bx + ay * by + az * bz


@njit(cache=True, inline="always")
def norm(x, y, z):
    """|v| = sqrt(x^2 + y^2 + z^2)."""
    return math.sqrt(x * x + y * y + z * z)


@njit(cache=True, inline="always")
def mat_vec(a, o, x, y, z):
    """A v with A = a[o:o+9] row-major."""
    return (
        a[o] * x + a[o + 1] * y + a[o + 2] * z,
        a[o + 3] * x + a[o + 4] * y + a[o + 5] * z,
        a[o + 6] * x + a[o + 7] * y + a[o + 8] * z,
    )


@njit(cache=True, inline="always")
def mat_t_vec(a, o, x, y, z):
    """A^T v with A = a[o:o+9] row-major."""
    return (
        a[o] * x + a[o + 3] * y + a[o + 6] * z,
        a[o + 1] * x + a[o + 4] * y + a[o + 7] * z,
        a[o + 2] * x + a[o + 5] * y + a[o + 8] * z,
    )


@njit(cache=True)
def mat_vec_n(a, o, v, out, n):
    """a[out:out+n] = A a[v:v+n] with A = a[o:o+n*n] row-major (n x n, accumulated from 0 by column)."""
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += a[o + n * i + j] * a[v + j]
        a[out + i] = s


@njit(cache=True, inline="always")
def inv3(a, ao, out, oo):
    """Inverse of the 3x3 block a[ao:ao+9] into out[oo:oo+9] (may be the same place), by cofactors;
    returns the determinant (0.0, and nothing written, when it is exactly zero)."""
    a00 = a[ao]
    a01 = a[ao + 1]
    a02 = a[ao + 2]
    a10 = a[ao + 3]
    a11 = a[ao + 4]
    a12 = a[ao + 5]
    a20 = a[ao + 6]
    a21 = a[ao + 7]
    a22 = a[ao + 8]
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if det == 0.0:
        return 0.0
    inv = 1.0 / det
    out[oo] = c00 * inv
    out[oo + 1] = (a02 * a21 - a01 * a22) * inv
    out[oo + 2] = (a01 * a12 - a02 * a11) * inv
    out[oo + 3] = c01 * inv
    out[oo + 4] = (a00 * a22 - a02 * a20) * inv
    out[oo + 5] = (a02 * a10 - a00 * a12) * inv
    out[oo + 6] = c02 * inv
    out[oo + 7] = (a01 * a20 - a00 * a21) * inv
    out[oo + 8] = (a00 * a11 - a01 * a10) * inv
    return det


@njit(cache=True)
def inv_n(p, a, out, n):
    """Inverse of the n x n row-major block p[a:a+n*n] into p[out:...] by Gauss-Jordan with
    partial pivoting; destroys the block at a.  Returns the product of the pivots (0: singular)."""
    for i in range(n * n):
        p[out + i] = 0.0
    for i in range(n):
        p[out + i * n + i] = 1.0
    det = 1.0
    for c in range(n):
        piv = c
        big = abs(p[a + c * n + c])
        for r in range(c + 1, n):
            v = abs(p[a + r * n + c])
            if v > big:
                big = v
                piv = r
        if big == 0.0:
            return 0.0
        if piv != c:
            for j in range(n):
                tmp = p[a + c * n + j]
                p[a + c * n + j] = p[a + piv * n + j]
                p[a + piv * n + j] = tmp
                tmp = p[out + c * n + j]
                p[out + c * n + j] = p[out + piv * n + j]
                p[out + piv * n + j] = tmp
            det = -det
        d = p[a + c * n + c]
        det *= d
        inv = 1.0 / d
        for j in range(n):
            p[a + c * n + j] *= inv
            p[out + c * n + j] *= inv
        for r in range(n):
            if r != c:
                f = p[a + r * n + c]
                if f != 0.0:
                    for j in range(n):
                        p[a + r * n + j] -= f * p[a + c * n + j]
                        p[out + r * n + j] -= f * p[out + c * n + j]
    return det


@njit(cache=True, inline="always")
def add_iuu(a, o, alpha, beta, ux, uy, uz):
    """a[o:o+9] += alpha I + beta u u^T."""
    a[o] += alpha + beta * ux * ux
    a[o + 1] += beta * ux * uy
    a[o + 2] += beta * ux * uz
    a[o + 3] += beta * uy * ux
    a[o + 4] += alpha + beta * uy * uy
    a[o + 5] += beta * uy * uz
    a[o + 6] += beta * uz * ux
    a[o + 7] += beta * uz * uy
    a[o + 8] += alpha + beta * uz * uz


@njit(cache=True, inline="always")
def iuu_vec(alpha, beta, ux, uy, uz, x, y, z):
    """(alpha I + beta u u^T) v = alpha v + beta (u . v) u."""
    uv = ux * x + uy * y + uz * z
    return alpha * x + beta * uv * ux, alpha * y + beta * uv * uy, alpha * z + beta * uv * uz


@njit(cache=True, inline="always")
def sub_iuu_sandwich(a, o, s, alpha, beta, u0, u1, u2):
    """a[o:o+9] -= K S K with K = alpha I + beta u u^T and S = a[s:s+9] symmetric:
    K S K = alpha^2 S + alpha beta (S u u^T + u u^T S) + beta^2 (u . S u) u u^T."""
    su0, su1, su2 = mat_vec(a, s, u0, u1, u2)
    usu = u0 * su0 + u1 * su1 + u2 * su2
    us = (u0, u1, u2)
    sus = (su0, su1, su2)
    for i in range(3):
        for j in range(3):
            a[o + 3 * i + j] -= (
                alpha * alpha * a[s + 3 * i + j]
                + alpha * beta * (sus[i] * us[j] + us[i] * sus[j])
                + beta * beta * usu * us[i] * us[j]
            )


# -- 3x3 blocks held in registers: 9-tuples, row-major ------------------------------------------
# The elimination of a chain (tether/chain.py) assembles, reduces and inverts one 3x3 block per
# joint.  Kept in the parameter block, every entry is a store and a reload (the compiler must
# assume any store to the block may change any other entry); as tuples they stay in registers.
# Each helper repeats the operation order of its in-block twin above, so results are the same bits.


@njit(cache=True, inline="always")
def iuu9(alpha, beta, ux, uy, uz):
    """alpha I + beta u u^T, each entry as :func:`add_iuu` adds it."""
    return (
        alpha + beta * ux * ux, beta * ux * uy, beta * ux * uz,
        beta * uy * ux, alpha + beta * uy * uy, beta * uy * uz,
        beta * uz * ux, beta * uz * uy, alpha + beta * uz * uz,
    )


@njit(cache=True, inline="always")
def load9(a, o):
    """The 3x3 block a[o:o+9]."""
    return (a[o], a[o + 1], a[o + 2], a[o + 3], a[o + 4], a[o + 5], a[o + 6], a[o + 7], a[o + 8])


@njit(cache=True, inline="always")
def store9(a, o, m):
    """a[o:o+9] = m."""
    a[o] = m[0]
    a[o + 1] = m[1]
    a[o + 2] = m[2]
    a[o + 3] = m[3]
    a[o + 4] = m[4]
    a[o + 5] = m[5]
    a[o + 6] = m[6]
    a[o + 7] = m[7]
    a[o + 8] = m[8]


@njit(cache=True, inline="always")
def add9(a, b):
    """a + b, entry by entry."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3], a[4] + b[4], a[5] + b[5],
            a[6] + b[6], a[7] + b[7], a[8] + b[8])


@njit(cache=True, inline="always")
def mat9_vec(a, x, y, z):
    """A v (as :func:`mat_vec`)."""
    return (
        a[0] * x + a[1] * y + a[2] * z,
        a[3] * x + a[4] * y + a[5] * z,
        a[6] * x + a[7] * y + a[8] * z,
    )


@njit(cache=True, inline="always")
def _sandwich_entry(a, s, alpha, beta, usu, ui, uj, sui, suj):
    return a - (alpha * alpha * s + alpha * beta * (sui * uj + ui * suj) + beta * beta * usu * ui * uj)


@njit(cache=True, inline="always")
def sub_iuu_sandwich9(a, s, alpha, beta, u0, u1, u2):
    """a - K S K with K = alpha I + beta u u^T and S symmetric (as :func:`sub_iuu_sandwich`)."""
    su0, su1, su2 = mat9_vec(s, u0, u1, u2)
    usu = u0 * su0 + u1 * su1 + u2 * su2
    return (
        _sandwich_entry(a[0], s[0], alpha, beta, usu, u0, u0, su0, su0),
        _sandwich_entry(a[1], s[1], alpha, beta, usu, u0, u1, su0, su1),
        _sandwich_entry(a[2], s[2], alpha, beta, usu, u0, u2, su0, su2),
        _sandwich_entry(a[3], s[3], alpha, beta, usu, u1, u0, su1, su0),
        _sandwich_entry(a[4], s[4], alpha, beta, usu, u1, u1, su1, su1),
        _sandwich_entry(a[5], s[5], alpha, beta, usu, u1, u2, su1, su2),
        _sandwich_entry(a[6], s[6], alpha, beta, usu, u2, u0, su2, su0),
        _sandwich_entry(a[7], s[7], alpha, beta, usu, u2, u1, su2, su1),
        _sandwich_entry(a[8], s[8], alpha, beta, usu, u2, u2, su2, su2),
    )


@njit(cache=True, inline="always")
def inv3_9(a):
    """(determinant, inverse) of a 3x3 block by cofactors (as :func:`inv3`); a zero determinant
    returns (0.0, a)."""
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = a
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if det == 0.0:
        return 0.0, a
    inv = 1.0 / det
    return det, (
        c00 * inv,
        (a02 * a21 - a01 * a22) * inv,
        (a01 * a12 - a02 * a11) * inv,
        c01 * inv,
        (a00 * a22 - a02 * a20) * inv,
        (a02 * a10 - a00 * a12) * inv,
        c02 * inv,
        (a01 * a20 - a00 * a21) * inv,
        (a00 * a11 - a01 * a10) * inv,
    )
