"""Summary functions of uncertainty studies (``scene -> dict of floats``, module level so that a
worker process or a Dask worker imports them by name; see :mod:`tetherlab.sweep`).

* :func:`deorbit_days`: the electrodynamic de-orbit run until the root body reaches the scene's
  ``[stop] altitude`` (200 km if none), :func:`tetherlab.benchmarks.deorbit.run_until_altitude`;
* :func:`closed_form_decay_days`: the closed-form decay of a rigid vertical electrodynamic tether
  (docs/effects-electrodynamic.md section 5, eq. 6) from the scene's values, no simulation: the
  known-distribution problem of the verification gate (with a dispersed current I the time is
  proportional to 1/I).
"""

from __future__ import annotations

import math

STOP_ALTITUDE_M = 200e3
DAY_S = 86400.0
MAX_DAYS = 200  # the run's duration: an upper bound, the stop event ends it


def _ed_params(scene) -> dict:
    for e in scene.effects:
        if e.name == "electrodynamic":
            return e.params_si
    raise ValueError(f"scene {scene.name!r} has no 'electrodynamic' effect; this summary needs one")


def closed_form_decay_days(scene) -> dict[str, float]:
    """Eq. (6): T = M sqrt(mu) (a0^(5/2) - a1^(5/2)) / (5 I L |K| cos i), a1 = R + stop altitude."""
    from .reuse import ParameterSample

    if isinstance(scene, ParameterSample):
        scene = scene.scene()
    from ..orbits.ed_decay import decay_time_s

    ed = _ed_params(scene)
    if scene.orbit is None or scene.orbit.elements is None:
        raise ValueError(f"scene {scene.name!r}: closed_form_decay_days needs [orbit] elements")
    el = scene.orbit.elements
    mass = sum(b.mass_kg for b in scene.bodies) + sum(t.mass_kg for t in scene.tethers)
    length = sum(t.length_m for t in scene.tethers)
    stop = scene.stop.altitude_m if scene.stop is not None and scene.stop.altitude_m is not None else STOP_ALTITUDE_M
    a1 = scene.central_body.radius_m + stop
    t = decay_time_s(mass, ed["current"], length, ed["dipole_strength"], el.i_rad, scene.central_body.mu_m3_s2, el.a_m, a1)
    return {"decay_days": t / DAY_S, "log_decay_days": math.log(t / DAY_S)}


def deorbit_run(scene, *, repack_values: bool = True):
    """The de-orbit of a scene or a parameter sample (tetherlab/uncertainty/reuse.py) until the root
    body reaches the stop altitude: as :func:`tetherlab.benchmarks.deorbit.run_until_altitude`
    (duration 200 d, the stop a terminal event), on the sample's prepared model.
    Returns (the integrator's result, the stop altitude in m)."""
    from ..pipeline import integrate_prepared
    from .reuse import ParameterSample, prepared

    sc = scene.base if isinstance(scene, ParameterSample) else scene
    stop = sc.stop.altitude_m if sc.stop is not None and sc.stop.altitude_m is not None else STOP_ALTITUDE_M
    prep, p = prepared(scene, {"duration": f"{MAX_DAYS} d", "stop.altitude": f"{stop} m"},
                       repack_values=repack_values)
    res, _ = integrate_prepared(prep, p, None)
    return res, stop


def deorbit_days(scene) -> dict[str, float]:
    """De-orbit time (d) to the scene's stop altitude, and the run's cost."""
    res, stop = deorbit_run(scene)
    if res.stopped_by is None:
        raise ValueError(f"de-orbit did not reach {stop / 1e3:g} km altitude within {MAX_DAYS} d "
                         f"(status {res.status}: {res.message})")
    return {"deorbit_days": float(res.t[-1]) / DAY_S, "integrate_wall_s": float(res.stats["wall_s"]),
            "n_steps": float(res.stats.get("n_accepted", math.nan))}


#: the runner may hand this summary parameter samples (one prepared model per worker)
deorbit_days.accepts_parameter_samples = True
