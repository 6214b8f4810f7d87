"""The micro-cantilever study's :func:`run` — both cases under each failure rule at each resolution
through the sweep, the FEM ladder in a process of its own beside them (:class:`_Background`), the
static csph ladders and the deletion run — and :func:`root_ladder`, the 3-D root ladder of
``workbench run microcantilever_root``."""
from __future__ import annotations

import xarray as xr

from ..common import check_resolutions
from ..sweep import Task, run_tasks
from .dataset import dataset
from .ladders import (CASES, FEM_FULL_PATH_3D, FEM_MAX, FEM_MAX_ROOT, FEM_RESOLUTIONS,
                      FEM_RESOLUTIONS_3D, FEM_STEP, NAME, QUICK_FEM_RESOLUTIONS, SCENE, SOLVERS,
                      STATIC_RESOLUTIONS_3D, default_resolutions, options_for, quick_scene,
                      rules_for, runs_rule, scene_for, solver_rules, static_resolutions)
from .scene import MicroCantilever
from .static import csph_static, fem_deletion, fem_ladder, root_ladder_path


def run(scene: MicroCantilever | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, fields=None, field_runs=None) -> xr.Dataset:
    """Run both cases under each failure rule at each resolution (``quick``: 2-D, the default
    rule, H/Δx = 5). ``fields`` (a folder): every run writes its particles as a ParaView series
    there (``field_runs``: only these (solver, resolution) pairs)."""
    scene = scene or SCENE()
    if quick:
        scene = quick_scene(scene)
    table = default_resolutions(scene, quick)
    solvers = list(solvers or table)  # quick: csph alone (ladders.QUICK_RESOLUTIONS)
    for s in solvers:
        if s not in SOLVERS:
            raise ValueError(f"solver: {s!r} is not supported by {NAME}; allowed: {', '.join(SOLVERS)}")
    if "csph" not in solvers:  # the gates, the FEM's window and the references are csph's
        solvers.insert(0, "csph")
    ladders = {s: check_resolutions(resolutions.get(s, table.get(s, table["csph"]))
                                    if isinstance(resolutions, dict)
                                    else (resolutions or table.get(s, table["csph"])))
               for s in solvers}
    res = sorted({r for lad in ladders.values() for r in lad})
    for r in res:  # a grain boundary thinner than the spacing is bad input, not a failed run
        scene.model(scene.H / r)
    rules = rules_for(ladders["csph"], quick)
    tasks, keys = [], []
    for solver in solvers:
        for case in CASES:
            for rule in solver_rules(solver, rules):
                sc = scene_for(scene, case, rule)
                for r in ladders[solver]:
                    if not runs_rule(rule, r, ladders[solver]):
                        continue
                    sc.model(scene.H / r)  # a crack band too narrow for the spacing: bad input
                    opts = options_for(sc, rule)
                    if fields is not None and (field_runs is None
                                               or (solver, r) in set(field_runs)):
                        opts["fields"] = str(fields)
                    tasks.append(Task.make(solver, sc, r, **opts))
                    keys.append((solver, case, rule, r))
    # gate 1's reference: the FEM ladder of the same grains — in 2-D after the runs, in 3-D
    # (minutes, one core) in a process of its own while the particle runs go on
    fem3d = _Background(fem_ladder, scene, FEM_RESOLUTIONS_3D, FEM_MAX, FEM_FULL_PATH_3D) \
        if scene.dim == 3 else None
    fem_failed = None
    try:
        outs = dict(zip(keys, run_tasks(tasks, scheduler, NAME)))
        if fem3d is not None:
            try:
                fem = fem3d.result()
            except BackgroundFailed as err:  # the particle runs are kept; gate 1 says why it has none
                fem, fem_failed = None, str(err)
        else:
            fem = fem_ladder(scene, QUICK_FEM_RESOLUTIONS if quick else FEM_RESOLUTIONS,
                             FEM_MAX if quick else FEM_MAX_ROOT)
    finally:
        if fem3d is not None:
            fem3d.close()
    # gate 2's csph: the static runs on the FEM's path (the full 2-D run); in 3-D the ladder of
    # elastic slopes, gate 1's observed order (the root region's first failures in 3-D:
    # root_ladder, hours on 2 cores)
    if quick:
        static = None
    elif scene.dim == 2:
        static = {r: csph_static(scene, r) for r in static_resolutions(ladders["csph"])}
    else:
        static = {r: csph_static(scene, r, fem_max=FEM_STEP) for r in STATIC_RESOLUTIONS_3D}
    # gate 6: the FEM with element deletion beside the particles (the full 2-D run)
    deletion = {c: fem_deletion(scene, c) for c in CASES} if scene.dim == 2 and not quick else None
    ds = dataset(scene, outs, rules, res, fem, static, deletion, solvers)
    if fem_failed is not None:
        ds.attrs["fem_reference_failed"] = f"3-D FEM ladder H/h = {FEM_RESOLUTIONS_3D}: {fem_failed}"
    if fields is not None:
        from pathlib import Path

        from workbench.fields import series_name

        written = [f"{series_name(t.scene.name, t.solver, t.resolution)}.pvd" for t in tasks
                   if t.writes_fields]
        ds.attrs["field_series"] = ", ".join(n for n in written if (Path(fields) / n).exists())
    return ds


def root_ladder(scene: MicroCantilever | None = None, resolutions=FEM_RESOLUTIONS_3D,
                fem_resolutions=None) -> xr.Dataset:
    """Gate 2 of the 3-D scene, apart from the default run: the FEM ladder (27-node hexahedra in
    3-D) and static csph at the same ``resolutions`` along :func:`.static.root_ladder_path`, each
    stopped at the root region's last first failure, in a dataset without particle runs whose
    :func:`.gates.gates` are gate 1's static slopes and gate 2's (the elastic slope, the load at the
    first failure in :func:`.static.root_region`, their observed orders). Hours on 2 cores in 3-D:
    at H/h = 10 the FEM's path takes about 20 minutes and csph's 7, at 15 the FEM's 53 minutes (11
    GB) and csph's 44 minutes (3.7 GB). ``fem_resolutions``: the FEM's ladder where it is not the
    same (the 2-D one goes a mesh further: :data:`.ladders.FEM_RESOLUTIONS`). ``workbench run
    microcantilever_root`` runs it (:mod:`studies.microcantilever_root`)."""
    scene = scene or SCENE()
    res = tuple(sorted(int(r) for r in resolutions))
    fres = res if fem_resolutions is None else tuple(sorted(int(r) for r in fem_resolutions))
    fem = fem_ladder(scene, fres, FEM_MAX, fres[:1], root_path=True)
    static = {r: csph_static(scene, r, path=root_ladder_path(scene), until_root_failure=True)
              for r in res}
    return dataset(scene, {}, ["compression"], [res[0]], fem, static)


class _Background:
    """``fn(*args)`` in a process of its own (spawned, daemonic: it ends with this one):
    :meth:`result` waits for it — or raises :class:`BackgroundFailed` (one line) when the process
    ends without a result (killed for memory, say) or ``fn`` raised; :meth:`close` ends it."""

    POLL = 1.0  # s between looks at whether the process is still there

    def __init__(self, fn, *args):
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")
        self.conn, child = ctx.Pipe(duplex=False)
        self.process = ctx.Process(target=_background_call, args=(child, fn, args), daemon=True)
        self.process.start()
        child.close()

    def result(self):
        while not self.conn.poll(self.POLL):  # a result, or the end of the pipe when it died
            if not self.process.is_alive() and not self.conn.poll(0):
                break
        try:
            ok, value = self.conn.recv()
        except (EOFError, OSError):
            self.process.join(10 * self.POLL)
            code = self.process.exitcode
            why = (f"killed by signal {-code}{': out of memory?' if code == -9 else ''}"
                   if code is not None and code < 0 else f"exit status {code}")
            raise BackgroundFailed(f"the process ended without a result ({why})") from None
        if not ok:
            raise BackgroundFailed(value)
        return value

    def close(self):
        if self.process.is_alive():
            self.process.terminate()
        self.process.join()
        self.conn.close()


class BackgroundFailed(RuntimeError):
    """A :class:`_Background` job that gave no result (the reason, one line)."""


def _background_call(conn, fn, args):
    try:
        conn.send((True, fn(*args)))
    except Exception as err:  # the reason travels back; the study records it
        conn.send((False, f"{type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}"))
    finally:
        conn.close()
