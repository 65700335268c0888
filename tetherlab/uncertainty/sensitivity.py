"""Global sensitivity with SALib: Sobol' first-order and total indices, Morris screening.

Both designs are drawn by SALib in the unit cube and mapped through the study's own marginals
(:meth:`Dispersion.ppf`), so the indices are those of the study's distributions, not of uniform
ranges.  Sobol' indices (Saltelli 2002, Jansen's total-effect estimator as in Saltelli et al.
2010; ``SALib.sample.sobol`` with scrambling, ``SALib.analyze.sobol``): N (d + 2) runs for base
sample N; the intervals are SALib's bootstrap ones (``num_resamples``, ``conf_level``).  Morris
(1991) elementary effects, Campolongo's mu* (``SALib.sample.morris``, ``SALib.analyze.morris``):
r (d + 1) runs for r trajectories; mu* in units of the output per unit of the input's probability
(the design lives on the unit cube), with a bootstrap interval.  Morris levels are mapped to the
centres of p equal-probability bins, (k + 1/2)/p, so no level falls on an infinite tail.

Sobol' indices assume independent inputs: a study with correlations is refused here.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .dispersions import U_MAX, U_MIN, Dispersion


def _problem(names: Sequence[str]) -> dict:
    return {"num_vars": len(names), "names": list(names), "bounds": [[0.0, 1.0]] * len(names)}


def sobol_design(d: int, n_base: int, seed: int) -> np.ndarray:
    """SALib's Saltelli design for Sobol' first and total indices: N (d + 2) points in [0, 1]^d."""
    from SALib.sample import sobol as sobol_sample

    x = sobol_sample.sample(_problem([f"x{i}" for i in range(d)]), n_base, calc_second_order=False,
                            scramble=True, seed=seed)
    return np.clip(x, U_MIN, U_MAX)


def sobol_indices(names: Sequence[str], y: np.ndarray, *, seed: int = 0, level: float = 0.95,
                  n_boot: int = 1000) -> dict[str, dict[str, float]]:
    """``{name: {S1, S1_conf, ST, ST_conf}}``; conf = half-width of the ``level`` interval."""
    from SALib.analyze import sobol as sobol_analyze

    r = sobol_analyze.analyze(_problem(names), np.asarray(y, dtype=float), calc_second_order=False,
                              num_resamples=n_boot, conf_level=level, seed=seed, print_to_console=False)
    return {n: {"S1": float(r["S1"][i]), "S1_conf": float(r["S1_conf"][i]),
                "ST": float(r["ST"][i]), "ST_conf": float(r["ST_conf"][i])} for i, n in enumerate(names)}


def morris_design(d: int, trajectories: int, levels: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(X on SALib's grid in [0, 1], the same mapped to bin centres in (0, 1))."""
    from SALib.sample import morris as morris_sample

    x = morris_sample.sample(_problem([f"x{i}" for i in range(d)]), trajectories, num_levels=levels, seed=seed)
    return x, 0.5 / levels + x * (1.0 - 1.0 / levels)


def morris_indices(names: Sequence[str], x: np.ndarray, y: np.ndarray, levels: int, *, seed: int = 0,
                   level: float = 0.95, n_boot: int = 1000) -> dict[str, dict[str, float]]:
    from SALib.analyze import morris as morris_analyze

    r = morris_analyze.analyze(_problem(names), x, np.asarray(y, dtype=float), num_resamples=n_boot,
                               conf_level=level, num_levels=levels, seed=seed, print_to_console=False)
    return {n: {"mu_star": float(r["mu_star"][i]), "mu_star_conf": float(r["mu_star_conf"][i]),
                "sigma": float(r["sigma"][i]), "mu": float(r["mu"][i])} for i, n in enumerate(names)}


def values_from_cube(dispersions: Sequence[Dispersion], u: np.ndarray) -> np.ndarray:
    """The marginals applied column by column (no copula: the inputs are independent here)."""
    return np.column_stack([d.ppf(u[:, j]) for j, d in enumerate(dispersions)])


def sobol_of_function(f: Callable[[np.ndarray], np.ndarray], dispersions: Sequence[Dispersion], n_base: int,
                      seed: int, level: float = 0.95) -> dict[str, dict[str, float]]:
    """Sobol' indices of a vectorised ``f(values)`` (n x d -> n) under the dispersions."""
    u = sobol_design(len(dispersions), n_base, seed)
    y = f(values_from_cube(dispersions, u))
    return sobol_indices([d.key for d in dispersions], y, seed=seed, level=level)


def run_sensitivity(study, out_dir, *, scheduler=None, workers=None, progress=True, level: float = 0.95) -> dict:
    """The study's [sensitivity] through the sweep (cache under ``out_dir/cache``); writes
    ``sensitivity.json`` and ``sensitivity.csv``; returns ``{quantity: {key: indices}}``."""
    import json
    from pathlib import Path

    import pandas as pd

    from ..sweep import resolve, run_sweep
    from .runner import build_scenes

    if study.correlation is not None:
        raise ValueError(f"{study.path}: 'sensitivity': Sobol' and Morris indices assume independent inputs; "
                         f"the study correlates {list(study.correlation.keys)} (remove [[correlation]] for this)")
    sens = {"method": "sobol", "samples": 64, "levels": 4, "seed": study.seed, **study.sensitivity}
    d = len(study.dispersions)
    if sens["method"] == "sobol":
        u = sobol_design(d, sens["samples"], sens["seed"])
        grid = None
    else:
        grid, u = morris_design(d, sens["samples"], sens["levels"], sens["seed"])
    inputs = [{disp.key: disp.scene_value(disp.ppf(np.array([u[i, j]]))[0]) for j, disp in enumerate(study.dispersions)}
              for i in range(u.shape[0])]
    scenes, early = build_scenes(study, inputs)
    bad = [i for i, r in enumerate(early) if r is not None]
    if bad:
        raise ValueError(f"{study.path}: sensitivity design point {bad[0]} is not a valid scene: {early[bad[0]].error}")
    res = run_sweep(scenes, resolve(study.summary), cache_dir=Path(out_dir) / "cache", scheduler=scheduler,
                    workers=workers, progress=progress, description=f"{study.name}: sensitivity")
    if res.failed:
        raise RuntimeError(f"{len(res.failed)} of {len(scenes)} sensitivity runs failed (indices need every "
                           f"run); first: {res.failed[0].error}")
    out = {}
    rows = []
    for q in study.quantities:
        y = np.array([r.summary[q] for r in res.records])
        if sens["method"] == "sobol":
            idx = sobol_indices(study.keys, y, seed=sens["seed"], level=level)
        else:
            idx = morris_indices(study.keys, grid, y, sens["levels"], seed=sens["seed"], level=level)
        out[q] = idx
        rows += [{"quantity": q, "key": k, **v} for k, v in idx.items()]
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    (Path(out_dir) / "sensitivity.json").write_text(json.dumps({"method": sens, "indices": out}, indent=1))
    pd.DataFrame(rows).to_csv(Path(out_dir) / "sensitivity.csv", index=False)
    return out
