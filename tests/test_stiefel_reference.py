"""Checks on the Stiefel-Scheifele reference file (references/stiefel/reference.json).

The file is built by references/stiefel/build_reference.py (heyoka binary128 + an independent
decimal-arithmetic Taylor integrator). This test only reads the JSON: it never imports heyoka.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from decimal import Decimal, localcontext
from pathlib import Path

import pytest

REF = Path(__file__).resolve().parents[1] / "references" / "stiefel" / "reference.json"

# Tetherlab paper, section 4.1, eq. (50)-(51) (initial state) and eq. (52): the published final
# position of Stiefel & Scheifele (1971), Table 2b, km.
EQ50_POSITION_KM = ("0.0", "-5888.9727", "-3400.0")
EQ51_VELOCITY_KM_S = ("10.691338", "0.0", "0.0")
EQ52_FINAL_POSITION_KM = ("-24219.0503", "227962.1064", "129753.4424")

# Printed constants of the problem definition (references/stiefel-scheifele.md).
PRINTED_CONSTANTS = {
    "mu_earth_km3_s2": "398601",
    "J2": "1.08265e-3",
    "R_earth_km": "6371.22",
    "mu_moon_km3_s2": "4902.66",
    "rho_moon_km": "384400",
    "sigma_moon_rad_s": "2.665315780887e-6",
}


@pytest.fixture(scope="module")
def ref() -> dict:
    return json.loads(REF.read_text())


def _dist_m(a, b) -> Decimal:
    with localcontext() as c:
        c.prec = 60
        return sum(((Decimal(p) - Decimal(q)) ** 2 for p, q in zip(a, b, strict=True)),
                   Decimal(0)).sqrt() * 1000


def test_structure(ref):
    for key in ("problem", "units", "t_final_days", "t_final_s", "n_orbits", "initial_state",
                "final_state", "second_method", "published", "heyoka_double", "provenance"):
        assert key in ref, key
    assert ref["units"] == {"length": "km", "time": "s", "velocity": "km/s"}
    assert ref["n_orbits"] == 50
    assert ref["t_final_days"] == "288.12768941"
    assert Decimal(ref["t_final_s"]) == Decimal("288.12768941") * 86400
    assert tuple(ref["initial_state"]["position_km"]) == EQ50_POSITION_KM
    assert tuple(ref["initial_state"]["velocity_km_s"]) == EQ51_VELOCITY_KM_S
    for block in ("final_state", "second_method"):
        st = ref[block]
        for k in ("position_km", "velocity_km_s"):
            assert len(st[k]) == 3
            assert len(st[k + "_float"]) == 3
            for s, f in zip(st[k], st[k + "_float"], strict=True):
                assert isinstance(s, str)
                assert float(Decimal(s)) == pytest.approx(f, rel=1e-15, abs=0)


def test_final_state_strings_carry_resolved_digits(ref):
    fs = ref["final_state"]
    for key, dec_key in (("position_km", "resolved_decimals_km"),
                         ("velocity_km_s", "resolved_decimals_km_s")):
        n = fs[dec_key]
        assert n >= 12  # at least 1e-12 km (nanometre level) resolved
        for s in fs[key]:
            assert -Decimal(s).as_tuple().exponent == n
        full = fs[key + "_full_binary128"]
        for s, f in zip(fs[key], full, strict=True):
            assert abs(Decimal(s) - Decimal(f)) <= Decimal(1).scaleb(-n) / 2


def test_provenance(ref):
    p = ref["provenance"]
    for k in ("oracle", "oracle_version", "numpy_version", "python_version", "command",
              "precision", "fp_type", "tolerance", "date_utc", "machine", "constants",
              "sigma_choice", "definition_file", "second_method_engine", "libmpdec_version"):
        assert k in p, k
        assert p[k] not in ("", None), k
    assert "mpmath_version" in p  # None when mpmath is not used (stated in mpmath_note)
    assert p["oracle"] == "heyoka.py"
    assert p["fp_type"] == "real128"
    assert float(p["tolerance"]) < 1e-30
    assert "build_reference.py" in p["command"]
    assert p["definition_file"].endswith("stiefel-scheifele.md")
    dt.datetime.strptime(p["date_utc"], "%Y-%m-%dT%H:%M:%SZ")
    for k, v in PRINTED_CONSTANTS.items():
        assert p["constants"][k] == v, k
    assert "printed" in p["sigma_choice"]


def test_two_independent_methods_agree(ref):
    fs, sm = ref["final_state"], ref["second_method"]
    d = _dist_m(fs["position_km_full_binary128"], sm["position_km"])
    assert d < Decimal("1e-3")  # metres: far below 1 mm required
    assert float(d) == pytest.approx(sm["distance_to_reference_m"], rel=1e-6, abs=1e-30)
    # the rounded strings agree too (they keep only digits on which both methods agree)
    assert _dist_m(fs["position_km"], sm["position_km"]) < Decimal("1e-3")
    # the second method's own convergence check
    assert sm["self_check"]["distance_to_main_m"] < 1e-3


def test_distance_to_published_eq52(ref):
    """Distance of the reference to the published value (paper eq. 52 / book Table 2b)."""
    d = _dist_m(ref["final_state"]["position_km_full_binary128"], EQ52_FINAL_POSITION_KM)
    assert tuple(ref["published"]["position_km"]) == EQ52_FINAL_POSITION_KM
    assert float(d) == pytest.approx(ref["published"]["distance_to_reference_m"], rel=1e-9)
    # The book tabulates 4 decimals of km (~8 significant digits): sub-metre agreement.
    assert d < 1


def test_double_precision_table(ref):
    rows = ref["heyoka_double"]["rows"]
    tols = [r["tol"] for r in rows]
    assert tols == pytest.approx([10.0**-k for k in range(4, 14)], rel=1e-12)
    for r in rows:
        for k in ("final_position_error_m", "n_steps", "mean_steps_per_orbit",
                  "wall_time_s_median", "order"):
            assert k in r, k
        assert r["n_steps"] > 0
        assert r["mean_steps_per_orbit"] == pytest.approx(r["n_steps"] / 50)
        assert r["wall_time_s_median"] > 0
        assert len(r["wall_time_s_all"]) == 3
        assert math.isfinite(r["final_position_error_m"]) and r["final_position_error_m"] > 0
    # tightest tolerance is accurate to well below a metre
    assert rows[-1]["final_position_error_m"] < 1.0
