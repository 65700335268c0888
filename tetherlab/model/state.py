"""The layout of the state vector: named blocks, the only thing that slices a state.

A Cowell state is ``y = [q, q', attitude, wheels]`` with ``q = q_trans = (r0, d_1 .. d_N, other
roots)`` (docs/model.md sections 4 and 12).  :class:`StateLayout` names every block of it:

=================  ==========================================  =================================
block              what                                        where (n = n_qt)
=================  ==========================================  =================================
``root.r``         position of root 0 (m, inertial)            ``[0, 3)``
``rods.d``         every rod's half-separation d_g (m)         ``[3, 3 + 3 N)``, tether by tether
``roots.r``        the other roots' positions (m)              ``[3 + 3 N, n)``
``root.v``         velocity of root 0 (m/s)                    ``[n, n + 3)``
``rods.dd``        the rods' rates d_g' (m/s)                  ``[n + 3, n + 3 + 3 N)``
``roots.v``        the other roots' velocities (m/s)           ``[n + 3 + 3 N, 2 n)``
``attitude.B``     rigid body B: quaternion (w, x, y, z, body  7 each, kernel body order, from
                   -> inertial) and omega (rad/s, body axes)   ``2 n``
``wheels``         every wheel's axial momentum (N m s)        ``n_wheels`` after the attitudes
``reel.T``         a spool-law reel on tether T: its deployed   2 each, after the wheels
                   length L (m) and dL/dt (m/s)
=================  ==========================================  =================================

The compiled kernels read the same offsets from the parameter block (header H_NQT, H_NSTATE,
H_OFF_ATT, H_OFF_WHL; per body BT_QOFF, BT_AOFF): :meth:`StateLayout.agrees_with` checks that
the two say the same.

The root-orbit block (``root.r`` and ``root.v``) is the one a formulation maps (DROMO elements,
the turning frame's components); everything else is the *pass-through* part, which
:meth:`StateLayout.orbit_split` and :meth:`StateLayout.orbit_join` take apart and put together in
one fixed order ``[q[3:], q'[3:], attitude, wheels]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Reel laws whose length is state (tether/reel_spool.py): the rest prescribe L(t).
SPOOL_LAWS = ("spool", "tension")


@dataclass(frozen=True)
class Block:
    """One named block of the state: ``y[start:stop]``."""

    name: str
    start: int
    stop: int

    @property
    def slice(self) -> slice:
        return slice(self.start, self.stop)

    @property
    def size(self) -> int:
        return self.stop - self.start


@dataclass(frozen=True)
class StateLayout:
    """Named blocks of a Cowell state (see the module docstring).

    ``rods``: rods per tether (kernel order); ``other_roots``: kernel indices of the roots after
    root 0; ``rigid``: (kernel body index, number of wheels) of every rigid body, kernel order;
    ``spools``: kernel indices of the tethers whose reel's length is state (a spool law,
    tether/reel_spool.py), in reel order.
    """

    rods: tuple[int, ...]
    other_roots: tuple[int, ...] = ()
    rigid: tuple[tuple[int, int], ...] = ()
    tether_names: tuple[str, ...] = ()
    body_names: tuple[str, ...] = ()
    spools: tuple[int, ...] = ()

    # -- sizes ---------------------------------------------------------------------------------
    @property
    def n_rods(self) -> int:
        return sum(self.rods)

    @property
    def n_qt(self) -> int:
        """Length of q_trans (the second-order half of the translational state)."""
        return 3 * (1 + self.n_rods + len(self.other_roots))

    @property
    def n_attitude(self) -> int:
        return 7 * len(self.rigid)

    @property
    def n_wheels(self) -> int:
        return sum(nw for _, nw in self.rigid)

    @property
    def n_spool_states(self) -> int:
        return 2 * len(self.spools)

    @property
    def size(self) -> int:
        return 2 * self.n_qt + self.n_attitude + self.n_wheels + self.n_spool_states

    @property
    def has_attitude(self) -> bool:
        return bool(self.rigid)

    # -- the blocks ------------------------------------------------------------------------------
    @property
    def root_r(self) -> slice:
        return slice(0, 3)

    @property
    def root_v(self) -> slice:
        return slice(self.n_qt, self.n_qt + 3)

    @property
    def q(self) -> slice:
        return slice(0, self.n_qt)

    @property
    def qd(self) -> slice:
        return slice(self.n_qt, 2 * self.n_qt)

    @property
    def rods_d(self) -> slice:
        return slice(3, 3 + 3 * self.n_rods)

    @property
    def rods_dd(self) -> slice:
        return slice(self.n_qt + 3, self.n_qt + 3 + 3 * self.n_rods)

    @property
    def first_order(self) -> slice:
        """The attitude, wheel and spool blocks (first order; empty for point masses without a
        spool-law reel)."""
        return slice(2 * self.n_qt, self.size)

    @property
    def attitude(self) -> slice:
        return slice(2 * self.n_qt, 2 * self.n_qt + self.n_attitude)

    @property
    def wheels(self) -> slice:
        a = 2 * self.n_qt + self.n_attitude
        return slice(a, a + self.n_wheels)

    @property
    def spool_states(self) -> slice:
        """Every spool-law reel's [L, L'] (2 each, reel order)."""
        return slice(self.size - self.n_spool_states, self.size)

    def spool_of(self, k: int) -> slice:
        """[L, L'] of the spool-law reel paying out tether k (kernel index)."""
        a = self.spool_states.start + 2 * self.spools.index(k)
        return slice(a, a + 2)

    def rod(self, g: int) -> slice:
        """d_g of global rod g (tethers in kernel order, rods from the root side)."""
        return slice(3 + 3 * g, 6 + 3 * g)

    def rod_rate(self, g: int) -> slice:
        return slice(self.n_qt + 3 + 3 * g, self.n_qt + 6 + 3 * g)

    def tether_rods(self, k: int) -> slice:
        """The rods' d of tether k, as one block (3 per rod)."""
        g0 = sum(self.rods[:k])
        return slice(3 + 3 * g0, 3 + 3 * (g0 + self.rods[k]))

    def tether_rates(self, k: int) -> slice:
        sl = self.tether_rods(k)
        return slice(self.n_qt + sl.start, self.n_qt + sl.stop)

    def root_offset(self, b: int) -> int:
        """Index in q_trans of root body ``b``'s position (b = 0 or one of ``other_roots``)."""
        if b == 0:
            return 0
        return 3 * (1 + self.n_rods) + 3 * self.other_roots.index(b)

    def root_position(self, b: int) -> slice:
        """Position of root body ``b`` (b = 0 or one of ``other_roots``)."""
        o = self.root_offset(b)
        return slice(o, o + 3)

    def root_velocity(self, b: int) -> slice:
        o = self.n_qt + self.root_offset(b)
        return slice(o, o + 3)

    def attitude_of(self, b: int) -> slice:
        """Quaternion (4) and omega (3) of rigid body ``b`` (kernel index)."""
        j = [body for body, _ in self.rigid].index(b)
        a = 2 * self.n_qt + 7 * j
        return slice(a, a + 7)

    def quaternion_of(self, b: int) -> slice:
        a = self.attitude_of(b).start
        return slice(a, a + 4)

    def omega_of(self, b: int) -> slice:
        a = self.attitude_of(b).start
        return slice(a + 4, a + 7)

    def wheels_of(self, b: int) -> slice:
        j = [body for body, _ in self.rigid].index(b)
        w0 = self.wheels.start + sum(nw for _, nw in self.rigid[:j])
        return slice(w0, w0 + self.rigid[j][1])

    def blocks(self) -> tuple[Block, ...]:
        """Every named block in state order (the tiling of ``[0, size)``)."""
        out = [Block("root.r", 0, 3)]
        for k, n in enumerate(self.rods):
            sl = self.tether_rods(k)
            out.append(Block(f"tether.{self._tname(k)}.d", sl.start, sl.stop))
        for b in self.other_roots:
            o = self.root_offset(b)
            out.append(Block(f"root.{self._bname(b)}.r", o, o + 3))
        out.append(Block("root.v", self.n_qt, self.n_qt + 3))
        for k, n in enumerate(self.rods):
            sl = self.tether_rates(k)
            out.append(Block(f"tether.{self._tname(k)}.dd", sl.start, sl.stop))
        for b in self.other_roots:
            o = self.n_qt + self.root_offset(b)
            out.append(Block(f"root.{self._bname(b)}.v", o, o + 3))
        for b, _ in self.rigid:
            sl = self.attitude_of(b)
            out.append(Block(f"attitude.{self._bname(b)}", sl.start, sl.stop))
        for b, nw in self.rigid:
            if nw:
                sl = self.wheels_of(b)
                out.append(Block(f"wheels.{self._bname(b)}", sl.start, sl.stop))
        for k in self.spools:
            sl = self.spool_of(k)
            out.append(Block(f"reel.{self._tname(k)}", sl.start, sl.stop))
        return tuple(blk for blk in out if blk.size > 0)

    def block(self, name: str) -> slice:
        """The slice of the block named ``name`` (see :meth:`blocks`)."""
        for blk in self.blocks():
            if blk.name == name:
                return blk.slice
        raise KeyError(f"state block {name!r}: expected one of {[b.name for b in self.blocks()]}")

    def _tname(self, k: int) -> str:
        return self.tether_names[k] if k < len(self.tether_names) else str(k)

    def _bname(self, b: int) -> str:
        return self.body_names[b] if b < len(self.body_names) and self.body_names[b] else str(b)

    # -- formulations: the root-orbit block and the pass-through part ----------------------------
    @property
    def n_passthrough(self) -> int:
        """Length of everything but the root orbit: ``[q[3:], q'[3:], attitude, wheels]``."""
        return self.size - 6

    def orbit_split(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(r0, v0, pass-through) of one Cowell state; the pass-through is
        ``[q[3:], q'[3:], attitude, wheels]``."""
        h = self.n_qt
        return y[0:3], y[h : h + 3], np.concatenate([y[3:h], y[h + 3 :]])

    def orbit_join(self, r, v, rest) -> np.ndarray:
        """The Cowell state of :meth:`orbit_split`'s parts."""
        nd = self.n_qt - 3
        return np.concatenate([r, rest[:nd], v, rest[nd:]])

    def passthrough_atol(self, atol: np.ndarray) -> np.ndarray:
        """The pass-through part of a Cowell-state tolerance vector (same order as the state)."""
        h = self.n_qt
        a = np.asarray(atol, float)
        return np.concatenate([a[3:h], a[h + 3 :]])

    # -- construction and the check against the parameter block ----------------------------------
    @classmethod
    def from_model(cls, model) -> "StateLayout":
        """The layout of a built model (its tethers, roots, rigid bodies in kernel order)."""
        return cls.from_parts(model.tethers, model.bodies, model.roots)

    @classmethod
    def from_parts(cls, tethers, bodies, roots) -> "StateLayout":
        """The layout of tethers and bodies in kernel order, ``roots`` the roots' body indices
        (root 0 first): what build_model packs the block from."""
        rigid = tuple((b, len(body.rigid.wheels)) for b, body in enumerate(bodies) if body.rigid is not None)
        return cls(
            rods=tuple(t.rods for t in tethers),
            other_roots=tuple(roots[1:]),
            rigid=rigid,
            tether_names=tuple(t.name for t in tethers),
            body_names=tuple(b.name for b in bodies),
            spools=tuple(k for k, t in enumerate(tethers) if getattr(t, "reel", None) is not None
                         and t.reel.law in SPOOL_LAWS),  # fmt: skip
        )

    def agrees_with(self, p: np.ndarray) -> list[str]:
        """What the parameter block says differently from this layout (empty: they agree)."""
        from ..kernel import layout as L

        bad = []

        def same(what, got, want):
            if int(got) != int(want):
                bad.append(f"{what}: block {int(got)}, layout {int(want)}")

        same("H_NQT", p[L.H_NQT], self.n_qt)
        same("H_NSTATE", p[L.H_NSTATE], self.size)
        same("H_NRODS", p[L.H_NRODS], self.n_rods)
        same("H_OFF_ATT", p[L.H_OFF_ATT], self.attitude.start)
        same("H_OFF_WHL", p[L.H_OFF_WHL], self.wheels.start)
        same("H_NRIGID", p[L.H_NRIGID], len(self.rigid))
        same("H_NWHEEL", p[L.H_NWHEEL], self.n_wheels)
        offb = int(p[L.H_OFF_BODY])
        roots = {0, *self.other_roots}
        rigid = {b for b, _ in self.rigid}
        for b in range(int(p[L.H_NBODY])):
            bt = offb + b * L.BT_SIZE
            same(f"body {b} BT_QOFF", p[bt + L.BT_QOFF], self.root_offset(b) if b in roots else -1)
            same(f"body {b} BT_AOFF", p[bt + L.BT_AOFF], self.attitude_of(b).start if b in rigid else -1)
        offt = int(p[L.H_OFF_TETH])
        for k in range(len(self.rods)):
            tb = offt + k * L.TT_SIZE
            same(f"tether {k} TT_ROD0", 3 + 3 * p[tb + L.TT_ROD0], self.tether_rods(k).start)
            same(f"tether {k} TT_NRODS", p[tb + L.TT_NRODS], self.rods[k])
        return bad
