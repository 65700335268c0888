"""tetherlab: space tether dynamics (TMED rod model) and its verification workbench."""

__version__ = "0.1.0"
