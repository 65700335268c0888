"""The verification report (tetherlab/report.py) as a page a reader can use: every image it shows
resolves to a file, every internal link has a target, and it loads in a real browser.

The fast test renders a small report from made-up results (the rendering, not the numbers, is
under test); the slow test opens the page in headless Chromium (`--dump-dom`) -- the report
`make verify` wrote if there is one, else the same small report -- and reads back, from a script
run in the page, how many images the browser actually decoded.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tomllib
from html.parser import HTMLParser
from pathlib import Path

import pytest

from tetherlab import report

ROOT = Path(__file__).resolve().parent.parent


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids, self.hrefs, self.imgs, self.tags = set(), [], [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append(tag)
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "a" and "href" in a:
            self.hrefs.append(a["href"])
        if tag == "img":
            self.imgs.append(a.get("src", ""))


def page_problems(path: Path) -> list[str]:
    """Images that do not resolve and internal links without a target in the page at ``path``."""
    page = _Page()
    page.feed(path.read_text())
    bad = [f"image {src!r} missing" for src in page.imgs if not (path.parent / src).is_file()]
    bad += [f"link {h!r} has no target" for h in page.hrefs if h.startswith("#") and h[1:] not in page.ids]
    bad += [f"link {h!r} has no file" for h in page.hrefs
            if not re.match(r"[a-z]+:|#", h) and not (path.parent / h.split("#")[0]).is_file()]
    return bad


def _small_report(tmp: Path) -> Path:
    """A report from made-up results with the real gate definitions, one figure, one study."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tetherlab import verify

    gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
    (tmp / "runs" / "libration-inplane").mkdir(parents=True)
    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [0, 1])
    fig.savefig(tmp / "runs" / "libration-inplane" / "angles.png")
    plt.close(fig)
    gate_rows = [{"gate": g, "value": 0.5 * v["threshold"], "threshold": v["threshold"], "unit": v["unit"],
                  "result": "PASS"} for g, v in gates.items()]  # fmt: skip
    cells = {("de421_low_degree", "de421_fit_error"): (120.0, "caught"),
             ("j2_sign", "heyoka_orbits_position"): (5e3, "caught"),
             ("j2_sign", "stiefel_cowell_best_error"): (0.4, "missed")}
    by_defect, by_gate, _ = verify.mutation_summary(cells, gates, {})
    sections = {sid: (title, [{"case": "a | b", "value": 1e-3}], 1.0) for sid, title, _fn in verify.CHECKS}
    doc = report.Document(
        gates=gates, gate_rows=gate_rows, sections=sections,
        figures=[("libration-inplane", [Path("runs/libration-inplane/angles.png")])],
        figure_rows=[{"case": "libration-inplane", "steps": 10}], figure_section=verify.FIGURE_SECTION,
        studies=[("catenary", "Catenary", "### Errors\n\n| n | e |\n|---|---|\n| 4 | 1e-3 |\n", 2.0)],
        controls=([{"defect": "(none)", "probe": "de421", "wall (s)": 1.0}], cells, by_defect, by_gate),
        toothless=verify.TOOTHLESS, retired=verify.RETIRED, gate_section=verify.gate_section, wall_s=321.0,
        commit=("0123456789abcdef", False), footer="commit 0123456789 | numpy x | date",
        matrix_md=verify.matrix_md(cells, gates, by_defect, by_gate),
    )  # fmt: skip
    out = tmp / "index.html"
    out.write_text(report.render_html(doc.markdown(), title="tetherlab verification report"))
    return out


def test_small_report_images_resolve_and_links_have_targets(tmp_path):
    page = _small_report(tmp_path)
    assert page_problems(page) == []
    text = page.read_text()
    # the summary at the top: gates passed, mutation score, wall time, commit
    head = text[: text.index('id="contents"')]
    for word in ("gates passed", "mutation score", "wall time", "0123456789"):
        assert word in head, word
    # every gate of references/gates.toml is in the table, linked to its definition and evidence
    gates = tomllib.loads((ROOT / "references" / "gates.toml").read_text())
    for gid in gates:
        assert f'href="#gate-{gid}"' in text and f'id="gate-{gid}"' in text, gid
    assert "<details" in text and "<table>" in text and "&lt;" not in text[: text.index("<body>")]
    assert text.count("<img") == 1  # the Markdown image became an <img>, not text


def test_page_problems_sees_a_broken_link_and_a_missing_image(tmp_path):
    # the checker itself must fail a bad page (its negative control)
    bad = tmp_path / "bad.html"
    bad.write_text('<h2 id="a">A</h2><a href="#a">ok</a><a href="#nowhere">x</a><img src="none.png">')
    problems = page_problems(bad)
    assert any("#nowhere" in p for p in problems) and any("none.png" in p for p in problems)
    assert not any("'#a'" in p for p in problems)


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return None


@pytest.mark.slow
@pytest.mark.skipif(_chromium() is None, reason="no headless Chromium on this machine "
                    "(Debian: apt-get install -y chromium); make verify installs nothing, so the check is skipped")
def test_report_loads_in_headless_chromium(tmp_path):
    real = ROOT / "reports" / "index.html"
    page = real if real.is_file() else _small_report(tmp_path)
    assert page_problems(page) == []
    # a copy beside the original (relative image paths keep resolving) with a probe script that
    # records, after load, how many images the browser decoded and how many internal links resolve
    probe = page.parent / "_browser_probe.html"
    probe.write_text(page.read_text().replace("</body>", """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const ok = imgs.filter(i => i.complete && i.naturalWidth > 0).length;
  const links = [...document.querySelectorAll('a[href^="#"]')];
  const dead = links.filter(a => !document.getElementById(decodeURIComponent(a.getAttribute('href').slice(1)))).length;
  document.body.setAttribute('data-probe', `images ${imgs.length} decoded ${ok} links ${links.length} dead ${dead}`);
});
</script></body>"""))
    try:
        dom = subprocess.run(
            [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--allow-file-access-from-files",
             "--virtual-time-budget=10000", "--dump-dom", probe.as_uri()],
            capture_output=True, text=True, timeout=120, check=False,
        ).stdout  # fmt: skip
    finally:
        probe.unlink()
    m = re.search(r'data-probe="images (\d+) decoded (\d+) links (\d+) dead (\d+)"', dom)
    assert m, f"the page did not load in Chromium (no probe result); DOM starts {dom[:300]!r}"
    n_img, n_ok, n_links, n_dead = map(int, m.groups())
    assert n_img >= 1 and n_ok == n_img, f"{n_img - n_ok} of {n_img} images did not load"
    assert n_links >= 1 and n_dead == 0
    assert "tetherlab verification report" in dom
