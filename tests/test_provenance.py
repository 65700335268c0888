"""Figures and reports carry their provenance (house style section 8): tetherlab/provenance.py."""

from __future__ import annotations

import re

from tetherlab.provenance import footer, git_commit, stamp_figure


def test_footer_names_commit_versions_machine_and_date():
    line = footer()
    commit, _ = git_commit()
    assert line.startswith(f"commit {commit}")
    for lib in ("numpy", "scipy", "numba", "machine"):
        assert lib in line
    assert re.search(r"\d{4}-\d{2}-\d{2} \d{2}:\d{2} UTC$", line)


def test_stamp_figure_writes_the_line_and_the_sources():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot([0, 1], [0, 1])
    stamp_figure(fig, "studies/example.py; oracle: none")
    texts = [t.get_text() for t in fig.texts]
    plt.close(fig)
    assert len(texts) == 1
    assert "sources: studies/example.py; oracle: none" in texts[0]
    assert texts[0].startswith("commit ")
