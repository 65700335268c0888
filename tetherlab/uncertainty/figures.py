"""Figures of an uncertainty study: histogram and ECDF per quantity (with the 5/50/95 % quantiles
and the deadlines), and the convergence of the mean's bootstrap interval width against N."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def study_figures(result, out: Path) -> list[Path]:
    from .statistics import ci_width_curve, fit_slope

    plt = _plt()
    paths = []
    for q in result.study.quantities:
        x = result.values(q)
        if x.size < 2:
            continue
        st = result.stats[q]
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
        a1.hist(x, bins=max(10, int(np.sqrt(x.size))), color="0.6", edgecolor="0.3")
        xs = np.sort(x)
        a2.step(xs, np.arange(1, xs.size + 1) / xs.size, where="post", color="k")
        for name, style in (("q05", ":"), ("q50", "--"), ("q95", ":")):
            for ax in (a1, a2):
                ax.axvline(st[name]["value"], ls=style, color="tab:blue")
        for dl in result.study.deadlines.get(q, ()):
            for ax in (a1, a2):
                ax.axvline(dl, color="tab:red")
        n_f = len(result.failed)
        a1.set_title(f"{q}: {x.size} samples, {n_f} failed")
        a1.set_xlabel(q)
        a2.set_xlabel(q)
        a2.set_ylabel("ECDF")
        a2.set_title("quantiles 5/50/95 % (blue), deadlines (red)")
        fig.tight_layout()
        p = out / f"{q}_distribution.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
        ns = sorted({int(n) for n in np.unique(np.geomspace(8, x.size, 12).astype(int))})
        rows = ci_width_curve(x, ns)
        if len(rows) >= 3:
            slope, se = fit_slope(rows)
            fig, ax = plt.subplots(figsize=(5, 3.8))
            ax.loglog([r[0] for r in rows], [r[1] for r in rows], "o-", label=f"bootstrap, slope {slope:.2f} +- {se:.2f}")
            n0, w0 = rows[0]
            ax.loglog([n0, rows[-1][0]], [w0, w0 * (rows[-1][0] / n0) ** -0.5], "k:", label="N^-1/2")
            ax.set_xlabel("N (first N samples)")
            ax.set_ylabel(f"95 % interval width of mean {q}")
            ax.legend()
            fig.tight_layout()
            p = out / f"{q}_convergence.png"
            fig.savefig(p, dpi=110)
            plt.close(fig)
            paths.append(p)
    return paths


def convergence_figure(curves: dict[str, list[tuple[int, float]]], slopes: dict[str, tuple[float, float]],
                       path: Path, ylabel: str) -> Path:
    """Interval width against N for several designs (replicated), with the fitted slopes."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for name, rows in curves.items():
        s, se = slopes[name]
        ax.loglog([r[0] for r in rows], [r[1] for r in rows], "o-", label=f"{name}: slope {s:.2f} +- {se:.2f}")
    ax.set_xlabel("N")
    ax.set_ylabel(ylabel)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
