"""The verification report as a document: Markdown written here, HTML rendered by markdown-it-py.

``make verify`` (tetherlab.verify) measures; this module lays the results out for a reader:

* a summary at the top (gates passed, mutation score, wall time, commit);
* a table of contents;
* the gate table, each gate linked to its definition (quantity, source, error budget, folded away
  in a ``<details>``) and to the section holding its table and figures;
* the negative controls: the matrix of deliberate defects (tetherlab.mutants) against gates;
* one section per check and per study, with its tables and figures;
* a footer with commit, library versions, machine and date (house style 8).

Markdown is rendered with markdown-it-py (CommonMark + tables); raw HTML is allowed, for the
``<details>`` blocks and the coloured results, because every string in it is written by
tetherlab itself.  Every heading gets an ``id`` (explicit ones for sections, a slug otherwise), so
every internal link has a target (tests/test_report.py checks it).
"""

from __future__ import annotations

import html
import re
from dataclasses import dataclass

CSS = """
body { font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #1d232a;
       max-width: 1180px; margin: 0 auto; padding: 1.5em 2em 4em; background: #fcfcfd; }
h1 { font-size: 1.9em; margin-bottom: .2em; }
h2 { border-bottom: 2px solid #dde3ea; padding-bottom: .2em; margin-top: 2.2em; }
h3 { margin-top: 1.6em; }
a { color: #0b5cad; text-decoration: none; } a:hover { text-decoration: underline; }
code { font-size: .92em; background: #eef1f4; padding: .05em .3em; border-radius: 3px; }
pre { background: #eef1f4; padding: .8em; overflow-x: auto; }
table { border-collapse: collapse; margin: .8em 0; font-size: .88em; display: block; overflow-x: auto; max-width: 100%; }
th, td { border: 1px solid #d5dbe2; padding: .25em .55em; text-align: left; vertical-align: top; }
th { background: #eef2f6; } tr:nth-child(even) td { background: #f6f8fa; }
img { max-width: 100%; height: auto; border: 1px solid #e3e7eb; margin: .5em 0; }
details { margin: .35em 0; padding: .3em .7em; border: 1px solid #e1e6eb; border-radius: 4px; background: #fff; }
details > summary { cursor: pointer; }
.summary { display: flex; flex-wrap: wrap; gap: .8em; margin: 1em 0 1.5em; }
.summary div { background: #fff; border: 1px solid #d5dbe2; border-radius: 6px; padding: .6em 1em; min-width: 11em; }
.summary b { display: block; font-size: 1.35em; }
.pass { color: #137333; font-weight: 600; } .fail { color: #b3261e; font-weight: 700; }
.skip { color: #8a6d00; } .toc { columns: 2; } footer { margin-top: 3em; color: #5f6b76; font-size: .85em; }
"""


def _slug(text: str) -> str:
    s = re.sub(r"<[^>]+>", "", text).lower()
    s = re.sub(r"[^a-z0-9]+", "-", s).strip("-")
    return s or "section"


def render_html(md_text: str, title: str) -> str:
    """Markdown -> a standalone HTML page (markdown-it-py, CommonMark + tables + raw HTML)."""
    from markdown_it import MarkdownIt

    md = MarkdownIt("commonmark", {"html": True}).enable("table")
    tokens = md.parse(md_text)
    seen: set[str] = set(re.findall(r'\bid="([^"]+)"', md_text))
    for i, tok in enumerate(tokens):
        if tok.type == "heading_open" and not tok.attrGet("id"):
            base = _slug(tokens[i + 1].content)
            slug, k = base, 2
            while slug in seen:
                slug, k = f"{base}-{k}", k + 1
            seen.add(slug)
            tok.attrSet("id", slug)
    body = md.renderer.render(tokens, md.options, {})
    return (f"<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{html.escape(title)}</title><style>{CSS}</style></head>\n<body>\n{body}</body></html>\n")  # fmt: skip


def _fmt(v) -> str:
    try:
        import numpy as np

        if isinstance(v, (float, np.floating)):
            return f"{float(v):.4g}"
    except ImportError:  # pragma: no cover
        pass
    return str(v)


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _empty(v) -> bool:
    if v is None or (isinstance(v, str) and v.strip().lower() in ("", "nan")):
        return True
    try:
        return v != v  # NaN
    except Exception:  # noqa: BLE001 - an odd object is a value
        return False


def table(rows) -> str:
    """A Markdown table of ``rows`` (dicts); columns empty or NaN in every row are left out and
    named under the table, and a single cell without a value reads "–", so a reader never meets
    a nan."""
    if not rows:
        return ""
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    dropped = [k for k in keys if all(_empty(r.get(k)) for r in rows)]
    keys = [k for k in keys if k not in dropped]
    if not keys:
        return f"(no values: every column is empty: {', '.join(map(str, dropped))})"
    lines = ["| " + " | ".join(_cell(k) for k in keys) + " |", "|" + "---|" * len(keys)]
    for r in rows:
        # a cell without a value (NaN, None, empty: not applicable to that row) reads as a dash
        lines.append("| " + " | ".join("–" if _empty(r.get(k)) else _cell(_fmt(r.get(k))) for k in keys) + " |")
    if dropped:
        lines += ["", f"*(left out, no value in any row: {', '.join(_cell(k) for k in dropped)})*"]
    return "\n".join(lines)


def _unit(u) -> str:
    """A gate's unit as a reader reads it: "1" is a ratio without unit."""
    return "ratio (no unit)" if str(u).strip() == "1" else _cell(u)


_RESULT = {"PASS": '<span class="pass">PASS</span>', "FAIL": '<span class="fail">FAIL</span>',
           "SKIPPED": '<span class="skip">SKIPPED</span>'}


@dataclass
class Document:
    gates: dict
    gate_rows: list
    sections: dict  # id -> (title, rows, wall_s)
    figures: list  # (scene name, [relative paths])
    figure_rows: list
    figure_section: dict
    studies: list  # (name, title, markdown, wall_s)
    controls: tuple  # (rows, cells, by_defect, by_gate)
    toothless: dict
    retired: dict
    gate_section: object  # gate id -> section id
    wall_s: float
    commit: tuple
    footer: str
    matrix_md: str
    descriptions: dict = None  # section id -> what the section checks, against what (a docstring)

    def _evidence(self, gid: str) -> str:
        """A link to the section with the gate's table and figure (plain text if not in this run)."""
        sec = self.gate_section(gid)
        present = set(self.sections) | {f"study-{s[0]}" for s in self.studies} | {"controls", "gates"}
        title = self.sections[sec][0] if sec in self.sections else next(
            (s[1] for s in self.studies if f"study-{s[0]}" == sec), sec)
        return f"[{_cell(title)}](#{sec})" if sec in present and sec != "gates" else f"{_cell(title)} (not run)"

    def markdown(self) -> str:
        from . import mutants

        n_pass = sum(r["result"] == "PASS" for r in self.gate_rows)
        n_fail = sum(r["result"] == "FAIL" for r in self.gate_rows)
        _rows, cells, by_defect, by_gate = self.controls
        active = mutants.names()
        caught = sum(1 for d in active if by_defect.get(d))
        commit, dirty = self.commit
        score = f"{caught} / {len(active)}" if cells else "not run"
        md = [
            "# tetherlab verification report", "",
            "Every number below is recomputed by `make verify` (`python -m tetherlab.verify`); the gates are "
            "defined in `references/gates.toml`, each with its source and error budget.", "",
            '<div class="summary">',
            f'<div>gates passed<b>{n_pass} / {len(self.gate_rows)}</b>{n_fail} failed</div>',
            f'<div>mutation score<b>{score}</b>deliberate defects caught</div>',
            f'<div>wall time<b>{self.wall_s / 60:.1f} min</b>{self.wall_s:.0f} s</div>',
            f'<div>commit<b><code>{commit[:10]}</code></b>{"uncommitted changes" if dirty else "clean tree"}</div>',
            "</div>", "",
            '<h2 id="contents">Contents</h2>', "",
            '<div class="toc">', "",
            "- [Gates](#gates)",
            "- [Negative controls (mutation matrix)](#controls)",
        ]
        for sid, (title, _r, _w) in self.sections.items():
            md.append(f"- [{title}](#{sid})")
        md.append("- [Section 4.3 scenes as shipped](#scenes)")
        for name, title, _t, _w in self.studies:
            md.append(f"- [{title}](#study-{name})")
        md += ["- [Retired gates](#retired)", "", "</div>", ""]

        # -- gates
        md += ['<h2 id="gates">Gates</h2>', "",
               "A gate passes when its value is at most its threshold. *Evidence* links to the section with the "
               "gate's table and figure; the gate's name opens its definition, source and error budget below the "
               "table.", "",
               "| gate | value | threshold | unit | result | evidence |", "|---|---|---|---|---|---|"]
        for r in self.gate_rows:
            gid = r["gate"]
            md.append(f"| [{gid}](#gate-{gid}) | {_fmt(r['value'])} | {_fmt(r['threshold'])} | {_unit(r['unit'])} | "
                      f"{_RESULT.get(r['result'], r['result'])} | {self._evidence(gid)} |")  # fmt: skip
        md += ["", "### Definitions, sources and error budgets", ""]
        for gid, g in self.gates.items():
            kind = f" ({g['kind']})" if g.get("kind") else ""
            md += [f'<details id="gate-{gid}"><summary><code>{gid}</code>{kind}: {html.escape(g["quantity"])}</summary>', "",
                   f"**Threshold:** {_fmt(g['threshold'])} {_unit(g['unit'])}  ", f"**Source:** {g['source']}  ",
                   f"**Error budget / reason:** {g.get('budget', '(none stated)')}  ",
                   f"**Evidence:** {self._evidence(gid)}", "", "</details>", ""]

        # -- negative controls
        md += ['<h2 id="controls">Negative controls (mutation matrix)</h2>', ""]
        if not cells:
            md += ["Not run (`--no-controls`).", ""]
        else:
            md += [
                "Each deliberate defect of `tetherlab/mutants.py` is switched on alone and the cheap probes of the "
                "gates on its code path are run (a probe is the gate's own measurement on fewer cases; see "
                "`tetherlab/verify/controls.py`, `PROBES`). **CAUGHT** = the gate fails under the defect while it passes "
                "without it; *missed* = the gate passes anyway; RAISED = the probe refused to run under the defect (the "
                "defect counts as caught, but no gate of that probe earns teeth by it); · = the defect's code is not "
                "on that gate's path. "
                f"Score: {score} defects caught.", "", self.matrix_md, "",
                "### The defects", "",
                table([{"defect": m.name, "what is wrong": m.defect, "where the switch is": m.where,
                        "what it violates": m.source, "status": m.status,
                        "caught by": ", ".join(sorted(set(by_defect.get(m.name, [])))) or "-"}
                       for m in mutants.MUTANTS.values()]), "",
                "### Gates that no deliberate defect reaches", "",
                "A gate that none of the defects above makes fail is not proven able to fail by this matrix: either "
                "no defect of the list touches what it measures, or the defects that do are too small for it. Each is "
                "listed with the reason (a gate listed without one fails `mutation_toothless_unexplained`):", "",
            ]  # fmt: skip
            rows = [{"gate": f"[{g}](#gate-{g})", "reason": self.toothless.get(g, "**no reason given**")}
                    for g in self.gates if not by_gate.get(g)]
            md += [table(rows), "", "<details><summary>Probe runs (wall time, values without a defect)</summary>", "",
                   table(_rows), "", "</details>", ""]

        # -- checks
        for sid, (title, rows, wall) in self.sections.items():
            md += [f'<h2 id="{sid}">{html.escape(title)}</h2>', ""]
            what = " ".join(((self.descriptions or {}).get(sid) or "").split())
            if what:
                md += [f"**What is checked, against what:** {html.escape(what)}", ""]
            mine = [g for g in self.gates if self.gate_section(g) == sid]
            if mine:
                md += ["**The gates of this section** (each number below its threshold passes):", ""]
                md += [f"- [`{g}`](#gate-{g}): {html.escape(self.gates[g]['quantity'])} "
                       f"(threshold {_fmt(self.gates[g]['threshold'])} {_unit(self.gates[g]['unit'])})" for g in mine]
                md += [""]
            md += [f"*(measured in {wall:.0f} s)*", "", table(rows), ""]
            for name, files in self.figures:
                if self.figure_section.get(name) == sid:
                    md += [f"**{name}** (scene `studies/scenes/{name}.toml`):", ""]
                    md += [f"![{name}]({f.as_posix()})" for f in files] + [""]
        md += ['<h2 id="scenes">Section 4.3 scenes as shipped</h2>', "",
               "The paper's section 4.3 scenes run as shipped; their figures are in the sections above.", "",
               table(self.figure_rows), ""]
        for name, title, text, secs in self.studies:
            md += [f'<h2 id="study-{name}">{html.escape(title)}</h2>', "", f"*(study `studies/{name}.py`, run in {secs:.0f} s)*",
                   "", text, ""]
        md += ['<h2 id="retired">Retired gates</h2>', "", table([{"gate": k, "why": v} for k, v in self.retired.items()]), "",
               "<footer>", "", self.footer, "", "</footer>", ""]
        return "\n".join(md)
