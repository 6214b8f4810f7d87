"""``workbench verify``: run the headline studies with every method that supports them, apply the
accuracy gates, write the datasets, the figures (accuracy against cost included) and the report."""
from __future__ import annotations

import logging
import time

import numpy as np
from pathlib import Path

from studies.figures import accuracy_vs_cost

from workbench import results
from . import report

log = logging.getLogger("workbench")

FIELD_RUNS = {"plate": {("csph", 10), ("fem", 4), ("fem", 8)}, "rc_beam": {("csph", 8)}}
"""The runs of ``workbench verify`` that write field output (study -> (solver, resolution) pairs):
the CSPH plate at H/Δx = 10 (in the quick ladder too) and the FEM plate's dynamic run (4 elements
across H in the quick ladder, 8 in the full one; the modal-only rungs write nothing); the RC
beam's csph impacts at 12.5 mm (the quick one: specimen B)."""


def run_study(name: str, outdir, quick: bool, solvers=None, resolutions=None, scene=None,
              scheduler: str | None = None, budget: float = 0.0, fields=False,
              field_runs=None, study=None, options=None) -> dict:
    """Run one study and write ``STUDY.nc`` and its figures; returns the report section.
    ``study``: the study module (default ``studies.get(name)``; a user's scene runs with the
    generic :mod:`studies.scene` and its own ``name``).

    With a ``budget`` (s), a solver's ladder is extended by one level at a time while its observed
    order is not settled and the predicted cost of the next level fits in what is left
    (:mod:`studies.convergence`); finished runs come from the run cache.

    ``fields`` (True, or a folder): the particle runs (``field_runs``: only these (solver,
    resolution) pairs; None: all) write their fields as ParaView series under ``OUT/fields/`` (or
    the folder); the section gets an off-screen snapshot where this machine can render, else a note
    saying where the fields are and why there is no picture (:func:`field_section`).

    ``options`` (solver -> {name: value}): the methods' options, for a study whose ``run`` takes
    them (a user's scene, :mod:`studies.scene`).
    """
    import inspect

    import studies
    from studies import convergence
    from studies.common import ladder

    study = studies.get(name) if study is None else study
    default_run = solvers is None and resolutions is None and scene is None  # N_GATES applies
    outdir = Path(outdir)
    field_dir = None
    field_kw = {}
    field_notes = []
    if fields:
        field_dir = outdir / "fields" if fields is True else Path(fields)
        if "fields" in inspect.signature(study.run).parameters:
            field_kw = dict(fields=field_dir, field_runs=field_runs)
        else:
            field_notes.append(f"Fields: the {name} study writes no field output.")
    opt_kw = {"options": options} if options else {}
    t0 = time.perf_counter()
    ds = study.run(scene=scene, solvers=solvers, resolutions=resolutions, quick=quick,
                   scheduler=scheduler, **field_kw, **opt_kw)
    written = ds.attrs.get("field_series")
    extended = []
    while budget > 0:
        left = budget - (time.perf_counter() - t0)
        if not hasattr(study, "SOLVERS"):
            break
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
                       scheduler=scheduler, **opt_kw)
    if written is not None:
        ds.attrs["field_series"] = written  # the extended ladders ran without field output
    # the dataset first (a failed write saves it in a fallback folder and says where:
    # results.SavedElsewhere), then the figures
    saved = results.write(ds, outdir / f"{name}.nc")
    rows = study.errors(ds)
    label = getattr(study, "ERROR_LABEL", "max relative error [-]")
    try:  # a figure that cannot be written (full disk): one line saying where the dataset is
        figures = list(study.plot(ds, outdir))
        if rows:
            figures.append(accuracy_vs_cost(rows, f"{name}: accuracy against cost",
                                            outdir / f"{name}_accuracy_vs_cost.png", label))
    except results.WRITE_ERRORS as err:
        raise results.PartlyWritten(f"the figures of {name} could not be written in {outdir} "
                                    f"({results.why(err)}); the dataset was saved to {saved}",
                                    saved) from None
    gates = study.gates(ds)
    declared = getattr(study, "N_GATES", {}).get(bool(quick))
    if declared is not None and default_run:
        from studies.common import count_gate

        gates = gates + [count_gate(name, gates, declared)]  # a vanished gate fails the study
    section = dict(name=name, gates=gates, rows=rows, figures=figures, error_label=label,
                   verdict="PASS" if all(g.passed for g in gates) else "FAIL", dataset=ds,
                   written=saved)
    if hasattr(study, "orders"):
        section["orders"] = study.orders(ds)
    if hasattr(study, "report_tables"):
        section["tables"] = study.report_tables(ds)
    section["notes"] = list(study.report_notes(ds)) if hasattr(study, "report_notes") else []
    if field_kw:
        field_notes += field_section(study, written or "", field_dir, outdir, figures)
    section["notes"] += field_notes
    if extended:
        section["notes"].append("Ladder extended automatically (order not settled): "
                                + ", ".join(extended) + ".")
    return section


def field_section(study, written: str, field_dir: Path, outdir: Path, figures: list) -> list[str]:
    """Report the field series a study wrote: render one snapshot (appended to ``figures``) where
    this machine can, and return the notes — where the series are (open the .pvd in ParaView) and,
    without a snapshot, why none could be rendered."""
    from workbench import fields

    names = [n.strip() for n in written.split(",") if n.strip()]
    try:
        where = field_dir.relative_to(outdir).as_posix()
    except ValueError:
        where = str(field_dir)
    notes = []
    if not names:
        return notes + [f"Fields: none were written to {where}/ (no run that asked for them "
                        "finished)."]
    listed = ", ".join(f"{where}/{n}" for n in names)
    view = dict(getattr(study, "FIELD_VIEW", {}))
    pick = view.pop("prefer", None)
    chosen = next((n for n in reversed(names) if pick and n.startswith(pick)), names[-1])
    png = outdir / f"{study.NAME}_fields_{Path(chosen).stem}.png"
    try:
        got, why = fields.render_series(field_dir / chosen, png, **view,
                                        title=f"{Path(chosen).stem} (deformed particles)")
    except Exception as err:  # a picture is a bonus: never fail the study for it
        got, why = None, f"rendering failed ({type(err).__name__}: {err})"
    if got is not None:
        figures.append(got)
        notes.append(f"Fields (particles: displacement, velocity, Cauchy and von Mises stress, ε_p "
                     f"and damage for J2; FEM mesh: vertex displacement and velocity) written as ParaView series: {listed} (open the .pvd in "
                     f"ParaView). Snapshot below: {Path(chosen).stem}, rendered off-screen.")
    else:
        notes.append(f"Fields (particles: displacement, velocity, Cauchy and von Mises stress, ε_p "
                     f"and damage for J2; FEM mesh: vertex displacement and velocity) written as ParaView series: {listed} (open the .pvd in "
                     f"ParaView). No snapshot in this report: {why}.")
    return notes


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
        # one representative run writes its fields (and the report shows a snapshot of it)
        fields = dict(fields=True, field_runs=FIELD_RUNS[name]) if name in FIELD_RUNS else {}
        sections.append(run_study(name, outdir, quick, scheduler=scheduler, budget=budget,
                                  **fields))
        for g in sections[-1]["gates"]:
            log.info("%s", g.line())
    try:
        md, _ = report.write(outdir, sections, quick, time.perf_counter() - t0)
    except results.WRITE_ERRORS as err:  # a full disk: one line naming where the datasets are
        saved = ", ".join(str(s["written"]) for s in sections)
        raise results.PartlyWritten(f"the report could not be written in {outdir} "
                                    f"({results.why(err)}); the datasets were saved to {saved}",
                                    Path(outdir)) from None
    failed = [g for s in sections for g in s["gates"] if not g.passed]
    print(f"report: {md} ({len(failed)} gate(s) failed)")
    return 1 if failed else 0
