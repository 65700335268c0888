"""The scene: what to simulate, read from a TOML file or a Python dictionary, validated once.

A scene says which central body, which effects, which bodies and tethers, where they start, how
to integrate and what to output.  :func:`load_scene` reads a TOML file (``docs/scenes.md`` is the
reference of every key); :meth:`Scene.from_dict` reads the same structure from Python, where any
quantity may be a string ("5 km") or an astropy Quantity (``5 * u.km``).  Both return a
:class:`Scene`: frozen dataclasses holding SI floats (angles in rad), unit suffixes in the field
names (``length_m``, ``mass_kg``).

Every check happens here, at load, before anything is integrated; every failure is a
:class:`~tetherlab.errors.SceneError` naming the dotted key, what was expected and what was got.
The dataclasses are the *output* of that validation: build them through :meth:`Scene.from_dict`
(or :func:`load_scene`) and change them through :meth:`Scene.replace`, which re-validates.

The package, one concept a file: ``data`` (the dataclasses and constants), ``keys`` (reading one
value, naming its key), ``load`` (the file and the dictionary, section by section), ``sections``,
``bodies``, ``tethers``, ``orbit`` (the sections), ``checks`` (the graph, the layout, what can
run), ``serialise`` (back to a dictionary).  The graph itself is tetherlab/model/topology.py.
"""

from __future__ import annotations

from ..errors import SceneError
from ..model.topology import LayoutStep
from .data import (
    ATTITUDE_FRAMES,
    CENTER_OF_MASS,
    CENTRAL_BODY_PRESETS,
    EQUILIBRIUM,
    EULER_SEQUENCES,
    FORMULATIONS,
    INTEGRATOR_METHODS,
    MAX_SANE_STRAIN,
    MOTIONS,
    QUADRATURE_RANGE,
    QUATERNION_NORM_TOL,
    RATE_FRAMES,
    SHAPES,
    SIDES,
    SINGULAR_AT_ORIGIN,
    TETHER_MODELS,
    TIME_ELEMENTS,
    ERROR_SCALES,
    WHEEL_TORQUE_CONTROL,
    Attitude,
    Body,
    CentralBody,
    Control,
    EffectUse,
    Elements,
    InitialShape,
    IntegratorSpec,
    Orbit,
    OutputSpec,
    Rigid,
    Scene,
    Stop,
    Tether,
    Vector3,
    Wheel,
)
from .load import load_scene

__all__ = [
    "ATTITUDE_FRAMES",
    "CENTER_OF_MASS",
    "CENTRAL_BODY_PRESETS",
    "EQUILIBRIUM",
    "EULER_SEQUENCES",
    "FORMULATIONS",
    "INTEGRATOR_METHODS",
    "MAX_SANE_STRAIN",
    "MOTIONS",
    "QUADRATURE_RANGE",
    "QUATERNION_NORM_TOL",
    "RATE_FRAMES",
    "SHAPES",
    "SIDES",
    "SINGULAR_AT_ORIGIN",
    "TETHER_MODELS",
    "TIME_ELEMENTS",
    "ERROR_SCALES",
    "WHEEL_TORQUE_CONTROL",
    "Attitude",
    "Body",
    "CentralBody",
    "Control",
    "EffectUse",
    "Elements",
    "InitialShape",
    "IntegratorSpec",
    "LayoutStep",
    "Orbit",
    "OutputSpec",
    "Rigid",
    "Scene",
    "SceneError",
    "Stop",
    "Tether",
    "Vector3",
    "Wheel",
    "load_scene",
]
