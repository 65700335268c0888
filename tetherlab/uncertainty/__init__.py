"""Uncertainty studies: dispersed scene keys, sampling, statistics with bootstrap intervals,
global sensitivity, on local processes or a Dask cluster (docs/uncertainty.md).

One concept a module: :mod:`.dispersions` (distributions, correlations, their validation),
:mod:`.samplers` (MC, Latin hypercube, Sobol'; extendable), :mod:`.study` (the study file),
:mod:`.runner` (samples -> scenes -> sweep -> statistics), :mod:`.statistics` (bootstrap
intervals, convergence), :mod:`.sensitivity` (SALib Sobol' and Morris), :mod:`.figures`,
:mod:`.summaries` (summary functions), :mod:`.verification` (the gate for the machinery).
"""

from .runner import run_study, sample_inputs
from .study import load_uncertainty_study

__all__ = ["load_uncertainty_study", "run_study", "sample_inputs"]
