"""``workbench verify``: run the headline studies with every method that supports them, apply the
accuracy gates, write the datasets, the figures (accuracy against cost included) and the report."""
from __future__ import annotations

import logging
import time

import numpy as np
from pathlib import Path

from . import plots, report, results

log = logging.getLogger("workbench")


def run_study(name: str, outdir, quick: bool, solvers=None, resolutions=None, scene=None,
              scheduler: str | None = None, budget: float = 0.0) -> dict:
    """Run one study and write ``STUDY.nc`` and its figures; returns the report section.

    With a ``budget`` (s), a solver's ladder is extended by one level at a time while its observed
    order is not settled and the predicted cost of the next level fits in what is left
    (:mod:`studies.convergence`); finished runs come from the run cache.
    """
    import studies
    from studies import convergence
    from studies.common import ladder

    study = studies.get(name)
    t0 = time.perf_counter()
    ds = study.run(scene=scene, solvers=solvers, resolutions=resolutions, quick=quick,
                   scheduler=scheduler)
    extended = []
    while budget > 0:
        left = budget - (time.perf_counter() - t0)
        current = {s: ladder(s, resolutions, study, quick) for s in study.SOLVERS if s != "analytic"}
        grow = {}
        for s in current:
            rows = sorted((r["resolution"], r["error"], r["wall_time"]) for r in study.errors(ds)
                          if r["solver"] == s)
            if len(rows) >= 3:
                res, err, wall = map(np.array, zip(*rows))
                nxt = convergence.extend(res, err, wall, left)
                if nxt is not None:
                    grow[s] = sorted(set(current[s]) | {nxt})
        if not grow:
            break
        resolutions = {**current, **grow}
        extended += [f"{s} to {max(v)}" for s, v in grow.items()]
        log.info("%s: order not settled, ladder extended: %s", name, ", ".join(extended[-len(grow):]))
        ds = study.run(scene=scene, solvers=solvers, resolutions=resolutions, quick=quick,
                       scheduler=scheduler)
    outdir = Path(outdir)
    results.write(ds, outdir / f"{name}.nc")
    figures = list(study.plot(ds, outdir))
    rows = study.errors(ds)
    label = getattr(study, "ERROR_LABEL", "max relative error [-]")
    if rows:
        figures.append(plots.accuracy_vs_cost(rows, f"{name}: accuracy against cost",
                                              outdir / f"{name}_accuracy_vs_cost.png", label))
    gates = study.gates(ds)
    section = dict(name=name, gates=gates, rows=rows, figures=figures, error_label=label,
                   verdict="PASS" if all(g.passed for g in gates) else "FAIL", dataset=ds)
    if hasattr(study, "orders"):
        section["orders"] = study.orders(ds)
    if hasattr(study, "report_tables"):
        section["tables"] = study.report_tables(ds)
    section["notes"] = list(study.report_notes(ds)) if hasattr(study, "report_notes") else []
    if extended:
        section["notes"].append("Ladder extended automatically (order not settled): "
                                + ", ".join(extended) + ".")
    return section


def verify(outdir="results", quick: bool = False, scheduler: str | None = None,
           budget: float = 0.0) -> int:
    """Exit status: 0 if every gate passed, 1 otherwise. The runs of a full verification go to a
    local dask cluster of the machine's cores unless ``scheduler`` says otherwise ('serial', or
    a scheduler address); ``--quick`` runs serially (a cluster's start-up would dominate)."""
    if scheduler is None:
        scheduler = "serial" if quick else "local"
    import studies

    t0 = time.perf_counter()
    sections = []
    for name in studies.HEADLINE:
        log.info("study %s%s", name, " (quick)" if quick else "")
        sections.append(run_study(name, outdir, quick, scheduler=scheduler, budget=budget))
        for g in sections[-1]["gates"]:
            log.info("%s", g.line())
    md, _ = report.write(outdir, sections, quick, time.perf_counter() - t0)
    failed = [g for s in sections for g in s["gates"] if not g.passed]
    print(f"report: {md} ({len(failed)} gate(s) failed)")
    return 1 if failed else 0
