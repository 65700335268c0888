"""tetherlab: space tether dynamics (TMED rod model) and its verification workbench.

What a user needs is here: :func:`load_scene` (a TOML file) or :class:`Scene` (``Scene.from_dict``),
:func:`simulate` returning a :class:`Result`, and the errors: :class:`SceneError` (bad input, at
load), :class:`SimulationError` (a run that failed; its ``.result`` keeps the outputs so far) and
:class:`RunDirError` (an output or run directory that cannot be used).
"""

__version__ = "0.1.0"

# The names below are imported when first used, so that ``import tetherlab`` stays fast (the
# pipeline imports numba and compiles kernels).
_LAZY = {
    "Scene": ("tetherlab.scene.data", "Scene"),
    "Result": ("tetherlab.result", "Result"),
    "SceneError": ("tetherlab.errors", "SceneError"),
    "SimulationError": ("tetherlab.pipeline", "SimulationError"),
    "RunDirError": ("tetherlab.runstore", "RunDirError"),
}


def load_scene(path):
    """Load and validate a scene file (see docs/scenes.md)."""
    from .scene import load_scene as _load

    return _load(path)


def simulate(scene, **kwargs):
    """Integrate a scene; see :func:`tetherlab.pipeline.simulate`."""
    from .pipeline import simulate as _simulate

    return _simulate(scene, **kwargs)


def __getattr__(name):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'tetherlab' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


__all__ = ["load_scene", "simulate", "Scene", "Result", "SceneError", "SimulationError", "RunDirError", "__version__"]
