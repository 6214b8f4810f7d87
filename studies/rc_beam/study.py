"""The RC beam study's :func:`run`: the particle runs of every specimen, solver and spacing of
:mod:`.ladders`, the kernel-reduction and modal runs and (full run) the slow impact, through the
sweep (run cache, dask, resume); their dataset is :func:`.dataset.dataset`."""
from __future__ import annotations

import dataclasses

import xarray as xr

from ..sweep import Task, run_tasks
from .dataset import dataset
from .ladders import (KERNEL_REDUCTION_SPECIMEN, MODAL_RESOLUTION, MODAL_SOLVERS, MODAL_SPECIMENS,
                      NAME, OPTIONS, QUICK_SPECIMENS, SCENE, SOLVERS, SPECIMENS, _ladders,
                      scene_for)
from .scene import RCBeam
from .slow_impact import slow_impact_scene, slow_impact_tasks


def run(scene: RCBeam | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, fields=None, field_runs=None) -> xr.Dataset:
    """Both specimens with each solver at each resolution (particles across H; ``quick``:
    12.5 mm and the first 0.5 ms). ``fields`` (a folder): the runs (``field_runs``: only these
    (solver, resolution) pairs) write their particles as ParaView series there."""
    scene = scene or SCENE()
    solvers = list(solvers or SOLVERS)
    for s in solvers:
        if s not in SOLVERS:
            raise ValueError(f"solver: {s!r} is not supported by {NAME}; allowed: {', '.join(SOLVERS)}")
    lad = _ladders(solvers, resolutions, quick)
    for s, res in lad.items():  # a spacing above the cover is bad input, not a failed run
        for r in res:
            scene.model(scene.H / r)
    tasks, keys = [], []
    for sp in QUICK_SPECIMENS if quick else SPECIMENS:
        sc = scene_for(scene, sp, quick)
        for s in solvers:
            for r in lad[s]:
                opts = dict(OPTIONS[s])
                if fields is not None and (field_runs is None or (s, r) in set(field_runs)):
                    opts["fields"] = str(fields)
                tasks.append(Task.make(s, sc, r, **opts))
                keys.append((s, sp, r))
    kr_keys = []
    if "sph" in solvers and not quick:
        sc = scene_for(scene, KERNEL_REDUCTION_SPECIMEN, quick)
        for r in lad["sph"]:
            tasks.append(Task.make("sph", sc, r, **OPTIONS["sph"], kernel_reduction=True))
            kr_keys.append(r)
    modal_keys = []
    if "csph" in solvers:
        for sp in MODAL_SPECIMENS[bool(quick)]:
            beam = dataclasses.replace(scene, specimen=sp, structure="beam", name=f"{NAME}_{sp}_beam")
            for s in MODAL_SOLVERS:
                opts = dict(integration="nodal") if s == "csph" else {}
                tasks.append(Task.make(s, beam, MODAL_RESOLUTION, **opts))
                modal_keys.append((s, sp))
    slow_tasks = slow_impact_tasks(slow_impact_scene(scene)) if "csph" in solvers and not quick else {}
    done = run_tasks(tasks + list(slow_tasks.values()), scheduler, NAME)
    slow = dict(zip(slow_tasks, done[len(tasks):]))
    done = done[:len(tasks)]
    outs = dict(zip(keys, done[:len(keys)]))
    kr = dict(zip(kr_keys, done[len(keys):len(keys) + len(kr_keys)]))
    modal = dict(zip(modal_keys, done[len(keys) + len(kr_keys):]))
    res = sorted({r for v in lad.values() for r in v})
    ds = dataset(scene, outs, solvers, res, quick, modal, kr, slow=slow)
    if fields is not None:
        from ..common import field_series

        ds.attrs["field_series"] = ", ".join(
            n for n in (field_series(t.scene, [t]) for t in tasks) if n)
    return ds
