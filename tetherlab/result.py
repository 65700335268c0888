"""The result of a run: time series, diagnostics, run statistics, and their files on disk.

On disk (``Result.save(dir)``; ``tetherlab run`` writes the same tables as Parquet datasets as it
goes, tetherlab/runstore.py, and :meth:`Result.load` reads either): ``timeseries.csv`` (every body, every tether node, strain and
axial force per rod, reaction per joint), ``diagnostics.csv`` (momentum, angular momentum,
energies, libration angles and their errors) and ``run.json`` (the scene, status and message,
run statistics and library versions).  Both CSV files are read back by ``pandas.read_csv``.
"""

from __future__ import annotations

import json
import platform
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from . import diagnostics as diag
from .kinematics import center_of_mass_rows, point_rows


def library_versions() -> dict:
    import astropy
    import numba
    import scipy

    import tetherlab

    return {
        "tetherlab": tetherlab.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "pandas": pd.__version__,
        "astropy": astropy.__version__,
        "machine": f"{platform.system()} {platform.machine()}",
    }


@dataclass
class Result:
    timeseries: pd.DataFrame
    diagnostics: pd.DataFrame
    stats: dict
    status: int
    message: str
    scene_dict: dict = field(default_factory=dict)
    meta: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status == 0

    @property
    def events(self) -> pd.DataFrame:
        """The located events of the run, in time order: ``t_s``, ``event`` (the component: a
        rod going slack, ``wheel.BODY.WHEEL.max_torque`` / ``.max_speed`` for a wheel limit,
        ``stop.altitude``) and ``side`` (``slack``/``taut``; ``entered``/``left`` for a limit
        starting or ceasing to act; empty for the stop)."""
        rows = self.stats.get("events", []) if isinstance(self.stats, dict) else []
        return pd.DataFrame(
            {"t_s": [float(e["t_s"]) for e in rows], "event": [str(e["event"]) for e in rows],
             "side": [str(e.get("side", "")) for e in rows]}
        )  # fmt: skip

    @classmethod
    def from_run(cls, scene, prep, t, Y, d, stats, status, message, p) -> "Result":
        model = prep.model
        cols: dict[str, np.ndarray] = {"t_s": np.asarray(t, float)}
        nrows = len(t)
        nb = len(model.bodies)
        # every joint and body at every row, from the compiled forest walk in one pass
        # (tetherlab/kinematics.py; the joints of every tether tile the rows' joint blocks)
        pts_rows = point_rows(model, Y)
        allj = pts_rows["joints"]
        bodies = pts_rows["bodies"]
        rots = pts_rows["rotations"]
        for b, body in enumerate(model.bodies):
            if not body.name or (b > 0 and not body.mass_kg > 0 and not body.fixed):
                continue
            for j, ax in enumerate("xyz"):
                cols[f"{body.name}.{ax}_m"] = bodies[:, b, j]
            for j, ax in enumerate("xyz"):
                cols[f"{body.name}.v{ax}_m_s"] = bodies[:, b, 3 + j]
            if body.rigid is not None:
                off = model.rigid_index[b]
                qn = Y[:, off : off + 4] / np.linalg.norm(Y[:, off : off + 4], axis=1, keepdims=True) if nrows else np.zeros((0, 4))
                for j, ax in enumerate("wxyz"):
                    cols[f"{body.name}.q{ax}"] = qn[:, j]
                for j, ax in enumerate("xyz"):
                    cols[f"{body.name}.omega_{ax}_rad_s"] = Y[:, off + 4 + j]
                for w in body.rigid.wheels:
                    h = Y[:, model.wheel_index[(b, w.name)]]
                    cols[f"{body.name}.{w.name}.speed_rad_s"] = h / w.inertia_kg_m2 - Y[:, off + 4 : off + 7] @ np.asarray(w.axis)
                    cols[f"{body.name}.{w.name}.momentum_N_m_s"] = h
        # tether nodes, rods and joints in the scene's order (from the `from` end), whatever the kernel's
        nodes = {}
        g_rod = 0
        g_joint = 0
        for k, tet in enumerate(model.tethers):
            pos = allj[:, g_joint : g_joint + tet.rods + 1, :3]
            rods = d["rods"][:, g_rod : g_rod + tet.rods]
            jr = d["joints"][:, g_joint : g_joint + tet.rods + 1]
            if tet.reversed:
                pos = pos[:, ::-1]
                rods = rods[:, ::-1]
                jr = jr[:, ::-1]
            nodes[tet.name] = pos
            for j in range(tet.rods + 1):
                for a, ax in enumerate("xyz"):
                    cols[f"{tet.name}.node{j}.{ax}_m"] = pos[:, j, a]
            for i in range(tet.rods):
                cols[f"{tet.name}.rod{i + 1}.strain"] = rods[:, i, 0]
                cols[f"{tet.name}.rod{i + 1}.axial_force_N"] = rods[:, i, 1]
            reaction = np.linalg.norm(jr, axis=2)  # the same reduction per joint, all joints at once
            for j in range(tet.rods + 1):
                cols[f"{tet.name}.joint{j}.reaction_N"] = reaction[:, j]
            g_rod += tet.rods
            g_joint += tet.rods + 1
        ts = _frame(cols, nrows)

        g = d["global"]
        dcols = {
            "t_s": np.asarray(t, float),
            "kinetic_J": g[:, diag.G_KE],
            "potential_J": g[:, diag.G_VG],
            "elastic_J": g[:, diag.G_VE],
            "energy_J": g[:, diag.G_E],
        }
        if model.rigid_index:
            dcols["rotational_J"] = g[:, diag.G_KROT]
        dcols.update(_rigid_diagnostics(model, Y, d, bodies, rots, nrows))
        for j, ax in enumerate("xyz"):
            dcols[f"momentum_{ax}_N_s"] = g[:, diag.G_PX + j]
        for j, ax in enumerate("xyz"):
            dcols[f"angmom_{ax}_kg_m2_s"] = g[:, diag.G_HX + j]
        if nrows:
            E0 = g[0, diag.G_E]
            # A system that starts at rest in a field-free frame has no energy or angular
            # momentum scale at t = 0: its relative errors are NaN (undefined), never 1e300.
            scaleE = max(abs(g[0, diag.G_KE]), abs(g[0, diag.G_VG]), abs(g[0, diag.G_VE]))
            dE = g[:, diag.G_E] - E0
            dcols["energy_error_rel"] = dE / scaleE if scaleE > 0 else np.full(nrows, np.nan)
            H = g[:, diag.G_HX : diag.G_HZ + 1]
            dH = np.linalg.norm(H - H[0], axis=1)
            h0 = float(np.linalg.norm(H[0]))
            dcols["angmom_error_rel"] = dH / h0 if h0 > 0 else np.full(nrows, np.nan)
            # |H| is mostly orbital in orbit; the system's own angular momentum about its centre
            # of mass is the scale that sees an error in the tether's rotation (gates.toml)
            h_int = diag.internal_angular_momentum_scale(model, Y[0])
            dcols["angmom_error_internal"] = dH / h_int if h_int > 0 else np.full(nrows, np.nan)
            # libration angles of each tether (root -> tip line) in the centre of mass's orbital
            # frame; NaN in free space, which has none (docs/model.md 7)
            rc, vc = center_of_mass_rows(model, pts_rows)
            for k, tet in enumerate(model.tethers):
                pos = nodes[tet.name]
                if diag.has_orbital_frame(model) and np.linalg.norm(np.cross(rc[0], vc[0])) > 0:
                    th, ph = diag.libration_angles(rc, vc, pos[:, 0], pos[:, -1], prep.sides[k])
                else:
                    th = ph = np.full(nrows, np.nan)
                dcols[f"{tet.name}.theta_rad"] = th
                dcols[f"{tet.name}.phi_rad"] = ph
            dcols["com_radius_m"] = np.linalg.norm(rc, axis=1)
            dcols.update(_orbital_columns(scene, model, np.asarray(t, float), rc, vc))
        dg = _frame(dcols, nrows)
        scene_dict = scene.to_dict() if hasattr(scene, "to_dict") else {}
        meta = {
            "versions": library_versions(),
            "model": {
                "rods": [t.rods for t in model.tethers],
                "tether_models": [t.model for t in model.tethers],
                "effects": model.effect_names,
                "quadrature": model.quadrature,
                "ref_radius_m": prep.ref_radius_m,
                "ref_period_s": prep.ref_period_s,
                "method": prep.method,
                "rtol": prep.rtol,
            },
            "effect_evaluations": _effect_counts(p, model),
            "effect_meta": model.effect_meta,  # e.g. ephemeris fit errors (forces/third_body.py)
        }
        return cls(ts, dg, stats, int(status), message, scene_dict, meta)

    # -- files ---------------------------------------------------------------------------------
    def save(self, out_dir) -> Path:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        self.timeseries.to_csv(out / "timeseries.csv", index=False, float_format="%.17g")
        self.diagnostics.to_csv(out / "diagnostics.csv", index=False, float_format="%.17g")
        run = {
            "status": self.status,
            "ok": self.ok,
            "message": self.message,
            "stats": self.stats,
            "scene": self.scene_dict,
            **self.meta,
        }
        (out / "run.json").write_text(json.dumps(run, indent=2, default=_json_default))
        return out

    @classmethod
    def load(cls, out_dir) -> "Result":
        """A result saved by :meth:`save` (CSV) or written by ``tetherlab run`` (Parquet datasets,
        tetherlab/runstore.py; an interrupted run loads with the rows computed so far)."""
        out = Path(out_dir)
        run = json.loads((out / "run.json").read_text())
        if run.get("reel"):  # phases of their own rod counts, read back as one table (reelstore.py)
            from .reelstore import read_tables

            ts, dg = read_tables(out)
        elif (out / "timeseries").is_dir():
            ts, dg = (_read_parts(out / name) for name in ("timeseries", "diagnostics"))
        else:
            ts = pd.read_csv(out / "timeseries.csv")
            dg = pd.read_csv(out / "diagnostics.csv")
        meta = {k: v for k, v in run.items() if k not in {"status", "ok", "message", "stats", "scene"}}
        status = run.get("status", 0 if run.get("state") == "complete" else -1)
        return cls(ts, dg, run.get("stats", {}), status, run.get("message", ""), run.get("scene", {}), meta)


class DeferredResult(Result):
    """A :class:`Result` whose tables and meta are built from the run's arrays when first read.

    A deployment keeps one Result per phase (tetherlab/deployment.py): building each one's ~300
    columns as it ends cost more than the phase's integration at 500 m rods (docs/deployment.md
    8d), and most uses read a few columns of a few phases.  ``build()`` returns the Result the
    phase would have had (:meth:`Result.from_run` on the phase's arrays, kept by the closure);
    it runs once, at the first read of ``timeseries``, ``diagnostics``, ``scene_dict`` or
    ``meta``, and gives the same numbers as building it at once.  ``stats``, ``status`` and
    ``message`` are known when the phase ends and are plain attributes."""

    def __init__(self, build, stats: dict, status: int, message: str):
        self._build = build
        self._tables = None
        self.stats = stats
        self.status = int(status)
        self.message = message

    def _built(self) -> tuple:
        if self._tables is None:
            r = self._build()
            self._tables = [r.timeseries, r.diagnostics, r.scene_dict, r.meta]
            self._build = None  # the phase's arrays are released with the closure
        return self._tables

    def _field(i: int, name: str):  # noqa: N805 (a property factory, called in the class body)
        def get(self):
            return self._built()[i]

        def put(self, value):
            self._built()[i] = value

        return property(get, put, doc=f"The phase's ``{name}``, built at its first read.")

    timeseries = _field(0, "timeseries")
    diagnostics = _field(1, "diagnostics")
    scene_dict = _field(2, "scene_dict")
    meta = _field(3, "meta")
    del _field


def _frame(cols: dict, nrows: int) -> pd.DataFrame:
    """The table of ``cols`` (name: column), as ``pd.DataFrame(cols)`` gives it.  Float columns
    are copied into one 2-D array first: pandas then builds one block instead of checking and
    stacking hundreds of columns one by one (a third of a short run's set-up at 32 rods)."""
    arrays = list(cols.values())
    if not all(isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == (nrows,) for a in arrays):
        return pd.DataFrame(cols)
    block = np.empty((nrows, len(arrays)))
    for j, a in enumerate(arrays):
        block[:, j] = a
    return pd.DataFrame(block, columns=list(cols), copy=False)


def _read_parts(folder: Path) -> pd.DataFrame:
    """The parts of a Parquet dataset in row order (part-000000, part-000001, ...)."""
    parts = sorted(folder.glob("part-*.parquet"))
    if not parts:
        return pd.DataFrame()
    return pd.concat([pd.read_parquet(f) for f in parts], ignore_index=True)


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def _rigid_diagnostics(model, Y, d, bodies, rots, nrows) -> dict:
    """Per rigid body: roll/pitch/yaw in its own orbit frame (3-2-1), the quaternion norm error,
    the commanded control torque; per wheel the motor torque and saturation flag; per tether end
    the force on the body (inertial) and, on a rigid body, its torque about G (body axes)."""
    from .diagnostics import has_orbital_frame, orbital_frame

    out: dict = {}
    if not model.rigid_index:
        return out
    wheel_col = 0
    for b, body in enumerate(model.bodies):
        if body.rigid is None:
            continue
        off = model.rigid_index[b]
        q = Y[:, off : off + 4]
        out[f"{body.name}.quat_norm_error"] = 1.0 - np.linalg.norm(q, axis=1)
        r = bodies[:, b, :3]
        v = bodies[:, b, 3:]
        # rows: radial, along-track, normal; NaN where there is no orbit frame (free space, r x v = 0)
        f = orbital_frame(r, v) if has_orbital_frame(model) else np.full((len(r), 3, 3), np.nan)
        O = np.stack([np.cross(-f[:, 2], -f[:, 0]), -f[:, 2], -f[:, 0]], axis=-1)  # columns o1, o2, o3
        C = np.einsum("nji,njk->nik", O, rots[:, b])  # body -> orbit
        out[f"{body.name}.roll_rad"] = np.arctan2(C[:, 2, 1], C[:, 2, 2])
        out[f"{body.name}.pitch_rad"] = np.arcsin(np.clip(-C[:, 2, 0], -1.0, 1.0))
        out[f"{body.name}.yaw_rad"] = np.arctan2(C[:, 1, 0], C[:, 0, 0])
        # the body's own rotational angular momentum about G, inertial: R (J_s omega_b + sum a_k h_k)
        # (the angmom_* columns add every part's orbital m r x v to it)
        JS = np.asarray(body.rigid.inertia_kg_m2, float) - sum(
            (w.inertia_kg_m2 * np.outer(w.axis, w.axis) for w in body.rigid.wheels), np.zeros((3, 3))
        )  # fmt: skip
        Lb = Y[:, off + 4 : off + 7] @ JS.T
        for w in body.rigid.wheels:
            Lb = Lb + np.outer(Y[:, model.wheel_index[(b, w.name)]], np.asarray(w.axis, float))
        L = np.einsum("nij,nj->ni", rots[:, b], Lb)
        for j, ax in enumerate("xyz"):
            out[f"{body.name}.angmom_rot_{ax}_kg_m2_s"] = L[:, j]
        for j, ax in enumerate("xyz"):
            out[f"{body.name}.control_{ax}_N_m"] = d["control"][:, b, j]
        for w in body.rigid.wheels:
            out[f"{body.name}.{w.name}.torque_N_m"] = d["wheels"][:, wheel_col, 0]
            out[f"{body.name}.{w.name}.saturated"] = d["wheels"][:, wheel_col, 1]
            wheel_col += 1
    kindex = {b.name: i for i, b in enumerate(model.bodies) if b.name}
    g_joint = 0
    for k, tet in enumerate(model.tethers):
        J0 = d["joints"][:, g_joint]
        Jn = d["joints"][:, g_joint + tet.rods]
        g_joint += tet.rods + 1
        parent, child = tet.parent, tet.tip_name
        ends = {parent: (-J0, tet.from_point_m), child: (Jn, tet.to_point_m)}
        for name, (F, pt) in ends.items():
            side = ("to" if name == parent else "from") if tet.reversed else ("from" if name == parent else "to")
            for j, ax in enumerate("xyz"):
                out[f"{tet.name}.{side}_force_{ax}_N"] = F[:, j]
            b = kindex[name]
            if model.bodies[b].rigid is not None:
                Fb = np.einsum("nji,nj->ni", rots[:, b], F)  # R^T F
                tq = np.cross(np.asarray(pt, float), Fb)
                for j, ax in enumerate("xyz"):
                    out[f"{tet.name}.{side}_torque_{ax}_N_m"] = tq[:, j]
    _ = nrows
    return out


def _orbital_columns(scene, model, t, rc, vc) -> dict:
    """Altitude and osculating elements of the centre of mass for a run about a central body
    (central gravity among its effects), and over the Earth its geodetic latitude, longitude and
    height (tetherlab/orbits/osculating.py)."""
    from .orbits import osculating

    central = getattr(scene, "central_body", None)
    if central is None or "central_gravity" not in model.effect_names:
        return {}
    out = {"altitude_m": np.linalg.norm(rc, axis=1) - central.radius_m}
    out.update(osculating.elements(central.mu_m3_s2, rc, vc))
    if central.name == "earth":
        theta0 = 0.0
        if scene.epoch is not None:
            from .environment.earth_orientation import earth_rotation_angle

            theta0 = earth_rotation_angle(scene.epoch)["era_rad"]
        lat, lon, height = osculating.geodetic(osculating.earth_fixed(t, rc, theta0))
        out.update(latitude_rad=lat, longitude_rad=lon, geodetic_height_m=height)
    return out


def _effect_counts(p, model) -> dict:
    from .forces import EFFECTS
    from .model.params import ParamView

    counts = ParamView(p).counters
    return {name: int(counts[spec.code]) for name, spec in EFFECTS.items()}
