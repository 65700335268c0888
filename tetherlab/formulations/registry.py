"""The formulations a run can integrate, each saying what it supports before it runs.

A formulation is an object with

* ``name``: what the run reports (``stats["formulation"]``);
* ``supports(model, facts) -> None | Refusal``: None when it can run the scene, else the reason
  (the scene key, what that key would need, what the scene has), raised by
  ``pipeline._formulation`` as the SceneError;
* ``rhs`` and ``events``: the compiled right-hand side and event function (``events`` None when
  the formulation cannot locate events);
* its state maps between Cowell states and its own (the formulation modules: only the root-orbit
  block of the StateLayout is mapped, every other block passes through).

:data:`CHOICES` maps the scene's ``integrator.formulation`` to the formulations tried in order:
``"dromo"`` is the sigma form where it applies (a lone point mass without events), else the time
form.  Adding a formulation: a module in this package (rhs, events, maps), a class here with its
``supports``, an entry in :data:`FORMULATIONS` and :data:`CHOICES`, the scene's spelling in
``scene.FORMULATIONS``, and its segment plan in ``pipeline`` (docs/architecture.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KEY = "integrator.formulation"


@dataclass(frozen=True)
class Refusal:
    """Why a formulation cannot run a scene: the SceneError's key, expected and got.
    ``final``: False when the next formulation of the scene's choice may still run it."""

    key: str
    expected: str
    got: str
    final: bool = True


@dataclass(frozen=True)
class SceneFacts:
    """What the formulations' checks need beyond the model (known once the state is laid out)."""

    requested: str  # integrator.formulation as the scene writes it
    y0: np.ndarray  # the initial Cowell state
    mu_m3_s2: float
    events: bool  # the scene has event components (kernel/events.py)
    max_step_s: float | None


class Cowell:
    name = "cowell"

    def supports(self, model, facts):
        return None

    @property
    def rhs(self):
        from .cowell import cowell_rhs

        return cowell_rhs

    @property
    def events(self):
        from ..kernel.events import system_events

        return system_events


def _has_orbit(model, facts) -> bool:
    lay = model.state
    r, v = facts.y0[lay.root_r], facts.y0[lay.root_v]
    return float(np.linalg.norm(np.cross(r, v))) > 0.0


class CowellOrbit:
    name = "cowell-orbit"

    def supports(self, model, facts):
        got = repr(facts.requested)
        if model.root_fixed:
            return Refusal(KEY, "'cowell' for a scene whose root body is fixed (it has no orbit to turn with)", got)
        if not _has_orbit(model, facts):
            return Refusal(KEY, "'cowell' for a root body with no orbital motion about the centre (r x v = 0: "
                           "no frame to turn with)", got)  # fmt: skip
        return None

    @property
    def rhs(self):
        from .cowell_orbit import cowell_orbit_rhs

        return cowell_orbit_rhs

    @property
    def events(self):  # |r0| and the rod tensions are frame invariant
        from ..kernel.events import system_events

        return system_events


def _dromo_refusal(model, facts):
    got = repr(facts.requested)
    if "central_gravity" not in model.effect_names:
        # DROMO integrates the Kepler motion about the central body analytically: without
        # central_gravity in [effects] it would add a force the scene did not name
        return Refusal(KEY, "'cowell' when [effects] does not name central_gravity (DROMO builds it in)", got)
    if model.root_fixed:
        return Refusal(KEY, "'cowell' for a scene whose root body is fixed (it has no orbit)", got)
    return None


class DromoSigma:
    """The sigma form: a lone point mass without events (docs/dromo.md section 7)."""

    name = "dromo-sigma"

    def supports(self, model, facts):
        common = _dromo_refusal(model, facts)
        if common is not None:
            return common
        if model.tethers or facts.events or len(model.bodies) != 1 or model.state.has_attitude:
            return Refusal(KEY, "one point mass without events (the sigma form)", repr(facts.requested), final=False)
        if facts.max_step_s is not None:
            return Refusal(
                "integrator.max_step", "no max_step with formulation 'dromo' on a point mass (the independent "
                "variable is the ideal anomaly; use 'dromo-time' to bound the time step)", f"{facts.max_step_s} s",
            )  # fmt: skip
        lay = model.state
        r, v = facts.y0[lay.root_r], facts.y0[lay.root_v]
        energy = 0.5 * float(v @ v) - facts.mu_m3_s2 / float(np.linalg.norm(r))
        if not energy < 0:
            return Refusal(KEY, "'dromo-time' for an orbit that is not elliptic (the sigma form schedules its "
                           "outputs on the osculating ellipse)", repr(facts.requested))  # fmt: skip
        return None

    events = None  # the sigma form's independent variable is not the time

    @property
    def rhs(self):
        from .dromo import dromo_sigma_rhs

        return dromo_sigma_rhs


class DromoTime:
    """The time form: any scene with an orbit; the attitude and wheel blocks pass through."""

    name = "dromo-time"

    def supports(self, model, facts):
        return _dromo_refusal(model, facts)

    @property
    def rhs(self):
        from .dromo import dromo_time_rhs

        return dromo_time_rhs

    @property
    def events(self):
        from .dromo import dromo_time_events

        return dromo_time_events


FORMULATIONS = {f.name: f for f in (Cowell(), CowellOrbit(), DromoSigma(), DromoTime())}
#: the scene's integrator.formulation -> the formulations tried, in order
CHOICES = {
    "cowell": ("cowell",),
    "cowell-orbit": ("cowell-orbit",),
    "dromo": ("dromo-sigma", "dromo-time"),
    "dromo-time": ("dromo-time",),
}


def choose(model, facts: SceneFacts):
    """The first formulation of the scene's choice that supports it, else its Refusal."""
    refusal = None
    for name in CHOICES[facts.requested]:
        form = FORMULATIONS[name]
        refusal = form.supports(model, facts)
        if refusal is None:
            return form
        if refusal.final:
            return refusal
    return refusal
