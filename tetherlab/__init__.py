"""tetherlab: space tether dynamics (TMED rod model) and its verification workbench."""

__version__ = "0.1.0"


def load_scene(path):
    """Load and validate a scene file (see docs/scenes.md)."""
    from .scene import load_scene as _load

    return _load(path)


def simulate(scene, **kwargs):
    """Integrate a scene; see :func:`tetherlab.pipeline.simulate`."""
    from .pipeline import simulate as _simulate

    return _simulate(scene, **kwargs)


__all__ = ["load_scene", "simulate", "__version__"]
