"""Sweeps: each (scene, solver, resolution, options) run is one task.

:func:`run_tasks` runs a list of tasks and returns their result dicts in order:

- serially in this process (``scheduler='serial'``, the default for a single task),
- on a local dask.distributed cluster of the machine's cores (``scheduler='local'``), one
  single-threaded worker process per core (numba inside each worker then runs one thread, so the
  cores are not oversubscribed),
- or on an existing cluster (``scheduler='tcp://host:8786'``, ``workbench run --scheduler``).

A failed task is a status in its result (``error: …``), never a lost sweep. Finished runs are kept in
the one run cache (:mod:`workbench.runcache`: keyed by the run spec and a hash of the solver's, the
core's and the scene's own code, not the studies'; each entry checksummed and verified before it is
served), so a re-run reuses them; ``WORKBENCH_CACHE`` moves the cache, ``WORKBENCH_NO_CACHE=1``
disables it.

Field output (``fields=<folder>``, ``field_frames``) is an option that changes no result: it is left
out of the cache key, and a task that asks for fields is always run (a cached result has no fields
on disk), its result then cached under the same key as the run without fields.

No lost work: a run is in the cache as soon as it finishes (written to a temporary file, synced,
renamed), before the next one starts, so a sweep that is interrupted (Ctrl-C) or killed resumes
from the cache when the same command is run again (a Ctrl-C always stops the sweep, even where
numba turns it into a ``SystemError`` or a solver into an error status:
:func:`studies.common.catching_interrupts`); a result served from the cache carries
``cached = True``. :func:`recording` collects, for the tasks finished inside it, whether each came
from the cache and its set-up and JIT times (the CLI prints them beside each run's wall time).

Progress: one tqdm bar over the runs with the time left (quiet where stderr is not a terminal,
:mod:`workbench.progress`) and a log line per finished run. :func:`check_scheduler` refuses a
scheduler address that cannot be reached, in seconds and in one line, before any work starts.
"""
from __future__ import annotations

import contextlib
import logging
import os
import socket
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from workbench import progress as bars
from workbench import runcache
from workbench.runcache import cache_dir  # noqa: F401 - where the CLI says finished runs are

from .common import SOLVER_ENTRY, catching_interrupts, run_solver, summary_status

log = logging.getLogger("workbench")
FIELD_OPTIONS = ("fields", "field_frames")
"""Solver options that only ask for field output: not part of the cache key (see module doc)."""


@dataclass(frozen=True)
class Task:
    """One run: a solver on a scene at a resolution, with solver options."""

    solver: str
    scene: object
    resolution: int
    options: tuple = field(default=())  # sorted (name, value) pairs

    @classmethod
    def make(cls, solver, scene, resolution, **options) -> "Task":
        return cls(solver, scene, int(resolution), tuple(sorted(options.items())))

    def label(self) -> str:
        return f"{self.scene.name} {self.solver} {self.resolution}"

    @property
    def writes_fields(self) -> bool:
        return any(k == "fields" and v is not None for k, v in self.options)

    def key(self) -> str:
        """The run cache's key of this run (:func:`workbench.runcache.key`); field output is left
        out."""
        options = {k: v for k, v in self.options if k not in FIELD_OPTIONS}
        return runcache.key(self.solver, self.scene, self.resolution, options,
                            solver_modules(self.solver))


def solver_modules(solver: str) -> tuple:
    """The modules whose package decides the results of ``solver`` (hashed into the cache key):
    the module of its entry in :data:`studies.common.SOLVER_ENTRY`, ``sph`` for the particle
    methods."""
    entry = SOLVER_ENTRY.get(solver)
    return (entry.split(":")[0],) if entry else ("sph",)


def _cache_get(task: Task):
    return runcache.load(task.key())


def _cache_put(task: Task, out: dict) -> None:
    """Store a finished run (:func:`workbench.runcache.store`: only ``ok`` runs, atomically)."""
    runcache.store(task.key(), out)


def execute(task: Task) -> dict:
    """Run one task (in this process or on a worker)."""
    return run_solver(task.solver, task.scene, task.resolution, **dict(task.options))


def _single_thread_numba():
    os.environ["WORKBENCH_PROGRESS"] = "0"  # a worker's runs draw no bars on the user's terminal
    try:
        import numba

        numba.set_num_threads(1)
    except Exception:
        pass
    return True


_RECORDERS: list[list] = []


@contextlib.contextmanager
def recording():
    """Collect a record per task :func:`run_tasks` finishes inside the block: a dict with
    ``scene``, ``solver``, ``resolution``, ``cached`` (served from the run cache), ``status``,
    ``wall_time`` (the solver's own), ``setup_time`` and ``jit_time`` (where the solver reports
    them)."""
    records: list[dict] = []
    _RECORDERS.append(records)
    try:
        yield records
    finally:
        _RECORDERS.remove(records)


def _total(value) -> float:
    try:
        import numpy as np

        v = np.asarray(value, float)
        return float(np.nanmax(v)) if v.ndim else float(v)
    except (TypeError, ValueError):
        return float("nan")


class Progress:
    """A progress bar over the runs of a sweep with the time left (tqdm, on stderr where it is a
    terminal: :mod:`workbench.progress`) and a log line per finished run."""

    def __init__(self, total: int, title: str):
        self.total, self.done, self.title = total, 0, title
        self.bar = bars.bar(total, title, unit="run")

    def update(self, task: Task, out: dict, cached: bool) -> None:
        self.done += 1
        log.info("[%d/%d] %s: %s%s, %.2f s", self.done, self.total, task.label(),
                 summary_status(out.get("status", "?")), " (cached)" if cached else "",
                 0.0 if cached else float(out.get("run_wall_time", float("nan"))))
        self.bar.update(1)
        rec = dict(scene=task.scene.name, solver=task.solver, resolution=task.resolution,
                   cached=bool(cached), status=summary_status(out.get("status", "?")),
                   wall_time=_total(out.get("wall_time", float("nan"))),
                   setup_time=_total(out.get("setup_time", float("nan"))),
                   jit_time=_total(out.get("jit_time", float("nan"))))
        for records in _RECORDERS:
            records.append(rec)

    def close(self) -> None:
        self.bar.close()


def default_scheduler() -> str:
    return os.environ.get("WORKBENCH_SCHEDULER", "serial")


def run_tasks(tasks: list[Task], scheduler: str | None = None, title: str = "sweep") -> list[dict]:
    """Run ``tasks``; results in the same order. Cached runs are taken from the cache."""
    scheduler = scheduler or default_scheduler()
    results: list[dict | None] = [None] * len(tasks)
    progress = Progress(len(tasks), title)
    try:
        with bars.logging_through_bars(), catching_interrupts():  # Ctrl-C always stops the sweep
            todo = []
            for i, t in enumerate(tasks):
                hit = None if t.writes_fields else _cache_get(t)
                if hit is not None:
                    hit["cached"] = True
                    results[i] = hit
                    progress.update(t, hit, cached=True)
                else:
                    todo.append(i)
            if todo and (scheduler == "serial" or len(todo) == 1):
                for i in todo:
                    out = execute(tasks[i])
                    _cache_put(tasks[i], out)  # in the cache before the next run starts
                    results[i] = out
                    progress.update(tasks[i], out, cached=False)
            elif todo:
                _run_on_dask([tasks[i] for i in todo], todo, results, scheduler, progress)
    finally:
        progress.close()
    return results  # type: ignore[return-value]


SCHEDULER_TIMEOUT = 5.0
"""Seconds :func:`check_scheduler` waits for a scheduler to answer."""


def check_scheduler(scheduler: str | None, timeout: float = SCHEDULER_TIMEOUT) -> str:
    """``scheduler`` ('serial', 'local', or a dask scheduler address, ``tcp://HOST:PORT`` or
    ``HOST:PORT``) checked before any work: an address must accept a connection within
    ``timeout`` s. :class:`~workbench.scenes.ParameterError` (one line: the address and what
    failed) otherwise. Returns the scheduler."""
    from workbench.scenes import ParameterError

    allowed = "allowed: serial, local, or the address of a running dask scheduler (tcp://HOST:PORT)"
    scheduler = scheduler or default_scheduler()  # WORKBENCH_SCHEDULER is checked the same way
    if scheduler in ("serial", "local"):
        return scheduler
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ParameterError(f"scheduler: {scheduler!r} is not allowed; {allowed}")
    text = scheduler if "://" in scheduler else f"tcp://{scheduler}"
    parts = urlsplit(text)
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host, port = None, None
    if parts.scheme not in ("tcp", "tls") or not host or port is None:
        raise ParameterError(f"scheduler: {scheduler!r} is not allowed; {allowed}")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as err:
        why = (f"no answer within {timeout:g} s" if isinstance(err, socket.timeout)
               else (err.strerror or str(err)))
        raise ParameterError(f"scheduler: cannot reach {text} ({type(err).__name__}: {why}); "
                             f"{allowed}") from None
    return scheduler


def _run_on_dask(tasks, index, results, scheduler, progress) -> None:
    from dask.distributed import Client, LocalCluster, as_completed

    if scheduler == "local":
        n = os.cpu_count() or 1
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR)
        client = Client(cluster)
    else:
        cluster = None
        check_scheduler(scheduler)
        client = Client(scheduler, timeout=f"{int(4 * SCHEDULER_TIMEOUT)}s")
    try:
        client.run(_single_thread_numba)
        futures = {client.submit(execute, t, pure=False, key=f"run-{t.key()}-{k}"): (k, t)
                   for k, t in zip(index, tasks)}
        for fut in as_completed(futures):
            k, t = futures[fut]
            try:
                out = fut.result()
            except Exception as err:  # a worker died: the run is a status, the sweep goes on
                out = {"status": f"error: worker failed: {type(err).__name__}: {err}"}
            _cache_put(t, out)
            results[k] = out
            progress.update(t, out, cached=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
