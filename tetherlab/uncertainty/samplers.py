"""Samplers: points in the unit cube (0, 1)^d, reproducible bit for bit and extendable.

Row i of ``points(n)`` never depends on n: asking for 2 000 samples after 1 000 gives the same
first 1 000 rows, hence the same scenes, hence the same sweep-cache entries (docs/uncertainty.md 2).

* ``mc`` (plain Monte Carlo): row i is drawn by its own generator, ``default_rng([seed, i])``
  (numpy's SeedSequence hashes the pair), so rows are independent streams and any worker can draw
  any row;
* ``lhs`` (Latin hypercube): blocks of ``block`` rows, block b an independent Latin hypercube of
  ``block`` points from ``default_rng([seed, b])``; a study of a whole number of blocks is a union
  of Latin hypercubes (each stratified on its own), and a partial last block is a prefix of a full
  one;
* ``sobol`` (scrambled Sobol', Owen scrambling from scipy.stats.qmc): one engine, one scrambling
  from ``seed``; the first 2^m points are drawn at once (``random_base2``, m = ceil(log2 n)) and the
  first n kept.  Because a Sobol' sequence is a sequence, the first n points of 2^m are the first
  n of 2^(m+1): extension is exact; the balance properties hold for n a power of two (the study
  warns otherwise).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import qmc

METHODS = ("mc", "lhs", "sobol")


class Sampler:
    """Draws ``points(n)`` (n x d, floats in [0, 1)); row i independent of n."""

    method = "?"

    def __init__(self, dim: int, seed: int):
        if not isinstance(dim, int) or dim < 1:
            raise ValueError(f"sampler dimension: expected a positive integer, got {dim!r}")
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ValueError(f"sampling.seed: expected a non-negative integer, got {seed!r}")
        self.dim, self.seed = dim, seed

    def points(self, n: int) -> np.ndarray:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"sampling.samples: expected a positive integer, got {n!r}")
        return self._points(int(n))

    def _points(self, n: int) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError


class MonteCarlo(Sampler):
    method = "mc"

    def _points(self, n):
        return np.array([np.random.default_rng([self.seed, i]).random(self.dim) for i in range(n)])


class LatinHypercube(Sampler):
    method = "lhs"

    def __init__(self, dim: int, seed: int, block: int = 64):
        super().__init__(dim, seed)
        if isinstance(block, bool) or not isinstance(block, int) or block < 2:
            raise ValueError(f"sampling.block: expected an integer >= 2, got {block!r}")
        self.block = block

    def _points(self, n):
        blocks = []
        for b in range(math.ceil(n / self.block)):
            engine = qmc.LatinHypercube(self.dim, rng=np.random.default_rng([self.seed, b]))
            blocks.append(engine.random(self.block))
        return np.concatenate(blocks)[:n]


class Sobol(Sampler):
    method = "sobol"

    def _points(self, n):
        engine = qmc.Sobol(self.dim, scramble=True, rng=np.random.default_rng(self.seed))
        return engine.random_base2(max(0, math.ceil(math.log2(n))))[:n]


def make_sampler(method: str, dim: int, seed: int, block: int = 64) -> Sampler:
    if method == "mc":
        return MonteCarlo(dim, seed)
    if method == "lhs":
        return LatinHypercube(dim, seed, block)
    if method == "sobol":
        return Sobol(dim, seed)
    raise ValueError(f"sampling.method: expected one of {', '.join(METHODS)}, got {method!r}")


class SharedSeedSampler(Sampler):
    """A deliberately wrong Monte Carlo sampler (negative control of the verification gate): each
    of ``workers`` workers draws its share of the rows from a generator seeded with the same seed,
    so the study holds every point ``workers`` times."""

    method = "mc-shared-seed"

    def __init__(self, dim: int, seed: int, workers: int = 4):
        super().__init__(dim, seed)
        self.workers = workers

    def _points(self, n):
        share = math.ceil(n / self.workers)
        return np.concatenate([np.random.default_rng(self.seed).random((share, self.dim))
                               for _ in range(self.workers)])[:n]
