"""The momenta-only pass of the remaps (momentum_remap.momentum_rows) against the columns the
deployment's invariants report (deployment._rows: the whole diagnostics and the reel table).

Both make the same products and sums in the same order (the reel's material corrections are one
function, tether/reel_diagnostics.material_momentum), so they must agree bit for bit: any
difference means the two have drifted apart, and the births' and retirements' remaps would no
longer restore the momenta the invariants report (docs/deployment.md 6.3, 8g)."""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab import diagnostics as diag
from tetherlab.deployment import _rows
from tetherlab.momentum_remap import momenta
from tetherlab.pipeline import prepare

from .helpers import import_study
from .test_reel_hub_laws import _two_speeds

_SPOKE = import_study("deployment_spoke")


def _states(prep, n: int = 5) -> np.ndarray:
    """The scene's initial state and n - 1 with every velocity component moved by up to 0.1 m/s
    (or rad/s): states off the start, where the rods' rates and the hub's spin all count."""
    rng = np.random.default_rng(7)
    lay = prep.model.state
    y0 = np.array(prep.y0, float)
    Y = np.repeat(y0[None, :], n, axis=0)
    Y[1:, lay.qd] += rng.uniform(-0.1, 0.1, size=(n - 1, lay.qd.stop - lay.qd.start))
    return Y


@pytest.mark.parametrize("rigid", [True, False], ids=["rigid hub", "point hub"])
def test_momenta_only_pass_equals_the_invariant_columns_bit_for_bit(rigid):
    prep = prepare(_two_speeds(rigid))  # four reels on one hub: the corrections summed over reels
    model = prep.model
    Y = _states(prep)
    t = 1.25
    out, d, bad = _rows(model, np.full(len(Y), t), Y)
    assert bad < 0
    corr = out[:, :, 9:15].sum(axis=1)
    g = d["global"]
    expected = np.hstack([g[:, diag.G_PX : diag.G_PX + 3] + corr[:, 0:3], g[:, diag.G_HX : diag.G_HX + 3] + corr[:, 3:6]])
    got = momenta(model, t, Y)
    assert got.shape == (len(Y), 6)
    assert np.array_equal(got.view(np.uint64), expected.view(np.uint64)), got - expected
    # the reel's corrections are not zero here (the lines pay out at 0.5-0.8 m/s): a pass that
    # dropped them would differ by m w/2 per reel, which this state makes visible
    assert np.abs(corr[:, 0:3]).max() > 0.0
