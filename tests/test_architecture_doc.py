"""docs/architecture.md section 9 says where each equation of the paper is coded: every file it
names exists and mentions each equation number of its row in an "eq." reference (ranges such as
"eqs. 24-34" count for every number in them), so a reader who greps the file finds it.

Negative control: a row pointing an equation at a file that never mentions it is reported.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "architecture.md"
_REF = re.compile(r"\beqs?\.\s*((?:\d+(?:\s*-\s*\d+)?'?(?:\s*,\s*|\s+and\s+|\s*))+)")


def _numbers(text: str) -> set[int]:
    """Every equation number an "eq. N" / "eqs. A-B, C" reference in ``text`` covers."""
    out: set[int] = set()
    for m in _REF.finditer(text):
        for a, b in re.findall(r"(\d+)(?:\s*-\s*(\d+))?", m.group(1)):
            lo, hi = int(a), int(b or a)
            if hi - lo < 40:  # a year or a section number read as a range is not an equation
                out.update(range(lo, hi + 1))
    return out


def _rows() -> list[tuple[set[int], str]]:
    section = DOC.read_text().split("## 9.")[1]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].startswith("eq"):
            rows.append((_numbers(cells[0]), cells[2].strip("`")))
    return rows


def _missing(rows) -> list[str]:
    bad = []
    for eqs, rel in rows:
        path = ROOT / rel
        if not path.is_file():
            bad.append(f"{rel}: no such file")
            continue
        lacking = sorted(eqs - _numbers(path.read_text()))
        if lacking:
            bad.append(f"{rel}: does not mention eqs. {lacking}")
    return bad


def test_every_listed_equation_is_found_in_its_file():
    rows = _rows()
    covered = set().union(*(e for e, _ in rows))
    assert covered >= set(range(1, 4)) | set(range(8, 48)) | {50, 51, 52}, sorted(covered)
    assert not _missing(rows)


def test_a_wrong_row_is_reported():
    assert _missing([({33}, "tetherlab/bodies/wheels.py")]) == ["tetherlab/bodies/wheels.py: does not mention eqs. [33]"]
    assert _numbers("eqs. 24-26 and eq. 47'") == {24, 25, 26, 47}
