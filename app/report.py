"""The verification report (``report.md`` and ``report.html``), written from the datasets and gate
records only."""
from __future__ import annotations

import base64
import html
import os
from pathlib import Path

import numpy as np

from workbench.results import atomic_write_text, cpu_model, git_revision


def _table(rows: list[dict], cols: list[tuple[str, str, str]]) -> list[list[str]]:
    out = [[c[1] for c in cols]]
    for r in rows:
        line = []
        for key, _, fmt in cols:
            v = r.get(key, "")
            if isinstance(v, float):
                v = "NaN" if not np.isfinite(v) else format(v, fmt)
            line.append(str(v))
        out.append(line)
    return out


def _md_table(t: list[list[str]]) -> str:
    lines = ["| " + " | ".join(t[0]) + " |", "|" + "---|" * len(t[0])]
    lines += ["| " + " | ".join(r) + " |" for r in t[1:]]
    return "\n".join(lines)


def _html_table(t: list[list[str]]) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in t[0])
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in t[1:])
    return f"<table><tr>{head}</tr>{body}</table>"


def cost_to_accuracy(rows: list[dict], target: float = 0.01) -> list[list[str]]:
    """Per solver, the cheapest run of the ladder whose error is at most ``target``: the wall time
    to a given accuracy (issue 4), or 'not reached' with the best error of the ladder."""
    out = [["solver", f"cheapest run within {100 * target:g} %", "its error", "wall time [s]"]]
    for solver in dict.fromkeys(r["solver"] for r in rows):
        mine = [r for r in rows if r["solver"] == solver and np.isfinite(r["error"])]
        ok = [r for r in mine if r["error"] <= target]
        if ok:
            r = min(ok, key=lambda r: r["wall_time"])
            out.append([solver, f"resolution {r['resolution']}", f"{r['error']:.2e}", f"{r['wall_time']:.3g}"])
        elif mine:
            best = min(mine, key=lambda r: r["error"])
            out.append([solver, "not reached on this ladder", f"best {best['error']:.2e}",
                        f"{best['wall_time']:.3g}"])
    return out


def write(outdir, sections: list[dict], quick: bool, wall_time: float) -> tuple[Path, Path]:
    """``sections``: per study, dict(name, verdict, gates (list of Gate), rows (error rows),
    orders (dict solver -> observed order), figures (paths), notes (list of str))."""
    outdir = Path(outdir)
    failed = sum(not g.passed for s in sections for g in s["gates"])
    n_gates = sum(len(s["gates"]) for s in sections)
    head = (f"Workbench verification{' (quick)' if quick else ''}: {n_gates - failed}/{n_gates} "
            f"gates passed. Git {git_revision()}, {os.cpu_count()} CPUs ({cpu_model()}), "
            f"{wall_time:.1f} s.")
    cols = [("solver", "solver", ""), ("resolution", "resolution", ""), ("error", "error", ".3e"),
            ("wall_time", "wall time [s]", ".3f")]
    md = ["# Verification report", "", head, ""]
    ht = ["<!doctype html><html><head><meta charset='utf-8'><title>Verification report</title>",
          "<style>body{font-family:sans-serif;max-width:70em;margin:auto}table{border-collapse:"
          "collapse}td,th{border:1px solid #bbb;padding:2px 8px}.PASS{color:green}.FAIL{color:red}"
          "img{max-width:100%}</style></head><body>",
          "<h1>Verification report</h1>", f"<p>{html.escape(head)}</p>"]
    for s in sections:
        md += [f"## {s['name']} — {s['verdict']}", ""]
        ht += [f"<h2>{html.escape(s['name'])} — <span class='{s['verdict']}'>{s['verdict']}</span></h2>"]
        for note in s.get("notes", []):
            md += [note, ""]
            ht += [f"<p>{html.escape(note)}</p>"]
        md += ["Gates:", ""] + [f"- {g.line()}" for g in s["gates"]] + [""]
        ht += ["<ul>"] + [f"<li class='{'PASS' if g.passed else 'FAIL'}'>{html.escape(g.line())}</li>"
                          for g in s["gates"]] + ["</ul>"]
        if s.get("rows"):
            t = _table(s["rows"], cols)
            md += [f"Error ({s.get('error_label', 'error')}) of every run:", "", _md_table(t), ""]
            ht += [f"<p>Error ({html.escape(s.get('error_label', 'error'))}) of every run:</p>",
                   _html_table(t)]
            t = cost_to_accuracy(s["rows"])
            md += ["Wall time to 1 % error:", "", _md_table(t), ""]
            ht += ["<p>Wall time to 1 % error:</p>", _html_table(t)]
        if s.get("orders"):
            text = ", ".join(f"{k} {v:.2f}" if np.isfinite(v) else f"{k} n/a (fewer than 3 resolutions)"
                             for k, v in s["orders"].items())
            md += ["Observed convergence orders (least squares over the ladder): " + text, ""]
            ht += ["<p>Observed convergence orders (least squares over the ladder): "
                   + html.escape(text) + "</p>"]
        for extra in s.get("tables", []):
            md += [extra["title"], "", _md_table(extra["table"]), ""]
            ht += [f"<p>{html.escape(extra['title'])}</p>", _html_table(extra["table"])]
        for fig in s.get("figures", []):
            fig = Path(fig)
            md += [f"![{fig.stem}]({fig.name})", ""]
            data = base64.b64encode(fig.read_bytes()).decode()
            ht += [f"<p><img alt='{fig.stem}' src='data:image/png;base64,{data}'></p>"]
    ht += ["</body></html>"]
    return (atomic_write_text(outdir / "report.md", "\n".join(md) + "\n"),
            atomic_write_text(outdir / "report.html", "\n".join(ht) + "\n"))
