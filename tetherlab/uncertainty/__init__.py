"""Uncertainty studies: dispersed scene keys, sampling, statistics with bootstrap intervals,
global sensitivity, on local processes or a Dask cluster (docs/uncertainty.md).

One concept a module: :mod:`.dispersions` (distributions, correlations, their validation),
:mod:`.samplers` (MC, Latin hypercube, Sobol'; extendable), :mod:`.study` (the study file),
:mod:`.runner` (samples -> scenes -> sweep -> statistics), :mod:`.statistics` (bootstrap
intervals, convergence), :mod:`.sensitivity` (SALib Sobol' and Morris), :mod:`.figures`,
:mod:`.summaries` (summary functions), :mod:`.reuse` (parameter-only samples on a prepared model),
:mod:`.verification` (the machinery's gates), :mod:`.verification_deorbit` (the de-orbit study of
make verify).
"""

from .runner import run_study, sample_inputs
from .study import load_uncertainty_study

__all__ = ["load_uncertainty_study", "run_study", "sample_inputs"]
