"""What every study shares: the solver registry, one guarded call per (scene, solver, resolution)
run, gate records, and the observed order of convergence.

A solver is a function ``solve(scene, resolution, **options) -> dict`` (see the study modules for
the keys each scene returns). A run that raises is a result, not a crash: :func:`run_solver` turns
the exception into ``status = 'error: …'`` and the sweep goes on.
"""
from __future__ import annotations

import contextlib
import functools
import importlib
import logging
import math
import numbers
import signal
import threading
import time
import traceback
from dataclasses import dataclass

import numpy as np

log = logging.getLogger("workbench")

# 'analytic' is handled by each study itself; 'fem' is the reference; every particle method of
# :data:`sph.METHODS` runs through the one particle driver.
SOLVER_ENTRY = {"fem": "fem_reference:solve"}
"""Solvers other than the particle methods: name -> "module:function"."""


def _particle_methods() -> tuple:
    from sph import METHODS

    return tuple(METHODS)


ALL_SOLVERS = ("analytic", "fem") + _particle_methods()


def solver_function(name: str):
    """``solve(scene, resolution, **options) -> dict`` of the solver ``name``."""
    if name in SOLVER_ENTRY:
        mod, fn = SOLVER_ENTRY[name].split(":")
        return getattr(importlib.import_module(mod), fn)
    if name not in _particle_methods():
        raise ValueError(f"solver: {name!r} is unknown; allowed: {', '.join(ALL_SOLVERS)}")
    from sph import driver

    return functools.partial(driver.solve, name)


_INTERRUPTED = threading.Event()
"""Set by the SIGINT handler of :func:`catching_interrupts`: the user pressed Ctrl-C."""


def interrupted(err: BaseException | None = None) -> bool:
    """Whether the user pressed Ctrl-C during a run: the flag of :func:`catching_interrupts` is
    set, or ``err`` is, wraps or was raised while handling a ``KeyboardInterrupt`` (numba turns
    an interrupt raised inside compiled code into a ``SystemError`` whose ``__cause__`` or
    ``__context__`` is the ``KeyboardInterrupt``; a solver may also swallow it whole, which only
    the flag sees)."""
    if _INTERRUPTED.is_set():
        return True
    seen = set()
    while err is not None and id(err) not in seen:
        if isinstance(err, KeyboardInterrupt):
            return True
        seen.add(id(err))
        err = err.__cause__ or err.__context__
    return False


@contextlib.contextmanager
def catching_interrupts():
    """Within the block (in the main thread, where Python's own SIGINT handler is in place), a
    Ctrl-C sets the flag :func:`interrupted` reads and then raises ``KeyboardInterrupt`` as
    Python's handler does, so that an interrupt is honoured even where compiled code or a solver
    turns it into an error status. The previous handler is restored after."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return

    def on_sigint(signum, frame):
        _INTERRUPTED.set()
        raise KeyboardInterrupt

    _INTERRUPTED.clear()
    signal.signal(signal.SIGINT, on_sigint)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        _INTERRUPTED.clear()


def run_solver(name: str, scene, resolution: int, **options) -> dict:
    """Call one solver once; never raises for a failed run. Adds ``wall_time`` if the solver did not
    and a ``status`` (``ok``, ``unstable: …``, ``diverged``, ``error: …``). A Ctrl-C is never a
    failed run: it raises ``KeyboardInterrupt`` (:func:`interrupted`), whatever the solver made
    of it."""
    t0 = time.perf_counter()
    try:
        _check_memory_of_run(name, scene, resolution)  # refused before it allocates anything
        out = dict(solver_function(name)(scene, resolution, **options))
    except Exception as err:  # a failed run is a result
        if interrupted(err):
            raise KeyboardInterrupt from err
        log.debug("%s", traceback.format_exc())
        out = {"status": f"error: {type(err).__name__}: {err}"}
    if interrupted():  # the solver swallowed the interrupt (an error status, say)
        raise KeyboardInterrupt
    wall = time.perf_counter() - t0
    out.setdefault("wall_time", wall)
    out.setdefault("status", "ok")
    out["run_wall_time"] = wall  # the whole call, set-up included
    status = summary_status(out["status"])
    log.info("run %-10s %-6s resolution=%-4s %7.2f s  %s", scene.name, name, resolution, wall, status)
    return out


def _check_memory_of_run(name: str, scene, resolution) -> None:
    """:func:`check_memory` where the scene has a model and the estimate can be made (a run the
    estimate cannot judge is left to the solver)."""
    from workbench.scenes import ParameterError

    if not hasattr(scene, "model") or not isinstance(resolution, numbers.Integral):
        return
    try:
        check_memory(name, scene, int(resolution))
    except ParameterError:
        raise
    except Exception:  # pragma: no cover - no estimate: no refusal
        log.debug("no memory estimate for %s %s", name, getattr(scene, "name", scene))


def summary_status(status) -> str:
    """One status for a run whose solver reports one per load: 'ok' or the first that is not."""
    if isinstance(status, str):
        return status
    status = [str(s) for s in status]
    return "ok" if all(s == "ok" for s in status) else next(s for s in status if s != "ok")


@dataclass
class Gate:
    """One accuracy gate as data: what was compared (``name``), the computed value (``observed``:
    an error, an order or an outcome), the ``tolerance`` and why (``reason``: the error the method
    should have), what the value is compared against and why that is independent of what it checks
    (``reference``), and whether it passed.

    ``kind`` says what a regression is for the gate (tests/test_gates.py feeds every gate one):
    ``error`` (:meth:`at_most`: an error the method has; three times it must fail), ``exact``
    (:meth:`at_most` with ``defect``: the method is exact, the observed value is round-off and the
    tolerance separates it from ``defect``, the smallest error of a method known to be wrong: a
    third of that must fail), ``order`` (:meth:`at_least`), ``outcome`` (:meth:`expect`: the
    other outcome must fail) and ``criterion`` (:meth:`criterion`: an acceptance criterion with no
    error model — a share, a ratio of two energies of the run — whose regression is the criterion
    violated). A gate whose run is missing or gave NaN fails (:meth:`missing`); it never
    disappears."""

    name: str
    observed: float
    tolerance: float
    reason: str
    passed: bool
    shown: str = ""  # how a yes/no gate reads in the report (see :meth:`expect`)
    reference: str = ""
    kind: str = "error"
    defect: float = float("nan")

    @classmethod
    def at_most(cls, name: str, observed: float, tolerance: float, reason: str,
                reference: str = "", defect: float | None = None) -> "Gate":
        """``observed`` (an error) at most ``tolerance``; NaN fails. ``defect``: see ``exact``."""
        observed = float(observed)
        ok = bool(np.isfinite(observed) and observed <= tolerance)
        if defect is None:
            return cls(name, observed, float(tolerance), reason, ok, reference=reference)
        return cls(name, observed, float(tolerance), reason, ok, reference=reference,
                   kind="exact", defect=float(defect))

    @classmethod
    def at_least(cls, name: str, observed: float, bound: float, reason: str,
                 reference: str = "") -> "Gate":
        """A lower bound (an observed order of convergence, say)."""
        observed = float(observed)
        ok = bool(np.isfinite(observed) and observed >= bound)
        return cls(name, observed, float(bound), reason, ok,
                   shown=f"{observed:.4g} (at least {bound:.4g})", reference=reference,
                   kind="order")

    @classmethod
    def expect(cls, name: str, observed: str, expected: str, reason: str,
               reference: str = "") -> "Gate":
        """A qualitative gate: an observed outcome (e.g. 'stable', 'unstable') against the one the
        literature predicts; ``observed`` is 1 where they differ, 0 where they agree."""
        ok = observed == expected
        return cls(name, 0.0 if ok else 1.0, 0.0, reason, ok,
                   shown=f"{observed} (expected {expected})", reference=reference, kind="outcome")

    @classmethod
    def criterion(cls, name: str, observed: float, bound: float, reason: str,
                  reference: str = "") -> "Gate":
        """An acceptance criterion: ``observed`` at most ``bound`` (NaN fails), where the bound is
        a requirement (the issue's, the physics') and not the error a method should have, and the
        observed value has no error model (a count of failures outside a region, which may be
        zero; a ratio of two energies of the run). Three times such a value is no regression of
        anything; its regression is the criterion violated (:meth:`regressed`)."""
        observed = float(observed)
        ok = bool(np.isfinite(observed) and observed <= bound)
        return cls(name, observed, float(bound), reason, ok,
                   shown=f"{observed:.4g} (criterion: at most {bound:.4g})", reference=reference,
                   kind="criterion")

    @classmethod
    def missing(cls, name: str, why: str, tolerance: float, reason: str,
                reference: str = "") -> "Gate":
        """A gate whose run is missing, failed or gave no value: it fails (observed NaN) and says
        why, rather than being left out."""
        return cls(name, float("nan"), float(tolerance), reason, False,
                   shown=f"not evaluated: {why}", reference=reference)

    def regressed(self, factor: float = 3.0) -> "Gate":
        """The same gate fed a regression: an ``error`` gate ``factor`` times its observed error;
        an ``exact`` gate its ``defect`` over ``factor``; an ``outcome`` gate the other outcome;
        an ``order`` gate the order less ``log(factor)/log(2)`` (``factor`` times the error at the
        finest of two rungs a factor 2 apart); a ``criterion`` the smallest value that violates it
        (the next float above its bound: no error model says what ``factor`` would mean)."""
        import dataclasses
        import math as _m

        if self.kind == "error":
            value = factor * self.observed
        elif self.kind == "exact":
            value = self.defect / factor
        elif self.kind == "criterion":
            value = float(np.nextafter(self.tolerance, np.inf))
            return dataclasses.replace(
                self, observed=value, passed=bool(value <= self.tolerance),
                shown=f"{value:.4g} (criterion: at most {self.tolerance:.4g})")
        elif self.kind == "outcome":
            return dataclasses.replace(self, observed=1.0 - self.observed, passed=not self.passed)
        else:  # order
            value = self.observed - _m.log(factor) / _m.log(2.0)
            return dataclasses.replace(self, observed=value,
                                       passed=bool(np.isfinite(value) and value >= self.tolerance))
        return dataclasses.replace(self, observed=value,
                                   passed=bool(np.isfinite(value) and value <= self.tolerance))

    def line(self) -> str:
        mark = "PASS" if self.passed else "FAIL"
        value = self.shown or f"{self.observed:.4g} (tolerance {self.tolerance:.4g})"
        return f"{mark}  {self.name}: {value} — {self.reason}"


def planned(status) -> np.ndarray:
    """Where a study meant to run (its status is anything but 'not run'): a gate on such a run is
    evaluated whatever the run gave (NaN fails it), never left out."""
    return np.asarray(status).astype(str) != "not run"


def count_gate(study: str, gates: list, declared: int) -> "Gate":
    """The gate on the gates: at least ``declared`` (the study's ``N_GATES``) were evaluated; fewer
    means one vanished (a run missing, a branch not taken) and fails."""
    n = len(gates)
    return Gate(f"{study}: gates evaluated against the {declared} the study declares", float(n),
                float(declared), "a gate never disappears: a missing or NaN run fails its gate",
                n >= declared, shown=f"{n} (declared {declared})",
                reference="the study's N_GATES, fixed in its module", kind="count")


def observed_order(h, err) -> float:
    """Least-squares slope of log(err) against log(h) over the finite, positive points (NaN if fewer
    than three)."""
    h = np.asarray(h, float)
    err = np.abs(np.asarray(err, float))
    ok = np.isfinite(err) & (err > 0) & np.isfinite(h) & (h > 0)
    if ok.sum() < 3:
        return float("nan")
    slope, _ = np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)
    return float(slope)


def error_rows(ds, error: str = "error") -> list[dict]:
    """A study's ``errors``: the finite error ``ds[error]`` of each (solver, resolution) run with
    its wall time, the rows of the accuracy-against-cost figure."""
    rows = []
    for s in ds.solver.values:
        for r in ds.resolution.values:
            e = float(ds[error].sel(solver=s, resolution=r))
            if np.isfinite(e):
                rows.append(dict(solver=str(s), resolution=int(r), error=e,
                                 wall_time=float(ds["wall_time"].sel(solver=s, resolution=r))))
    return rows


def check_resolutions(resolutions) -> list[int]:
    """The resolutions as integers >= 1 (:class:`~workbench.scenes.ParameterError` otherwise, one
    line); an empty list is refused."""
    from workbench.scenes import ParameterError

    allowed = ("allowed: integers >= 1 (intervals across the scene's length: spacing length/r; a "
               "spacing larger than the body is not a discretisation)")
    if isinstance(resolutions, (str, bytes)) or not hasattr(resolutions, "__iter__"):
        resolutions = [resolutions]
    out = []
    for r in resolutions:
        if isinstance(r, bool) or not isinstance(r, numbers.Real) or (
                isinstance(r, float) and not (math.isfinite(r) and r == int(r))):
            raise ParameterError(f"resolution: {r!r} is not an integer; {allowed}")
        r = int(r)
        if r < 1:
            raise ParameterError(f"resolution: {r} is out of range; {allowed}")
        out.append(r)
    if not out:
        raise ParameterError(f"resolution: the list is empty; {allowed}")
    return out


# -- what a run will need, checked before any work starts ----------------------------------------

BYTES_PER_POINT = {
    2: {"particle": 8_000, "fem": 20_000},
    3: {"particle": 50_000, "fem": 200_000},
}
"""Memory one particle (or FEM node) of a run needs, bytes, incl. neighbour lists and gradient
tables (particles) or the sparse tangent and its factorisation (FEM). Particles: the peak-RSS
increase of discretising and building a body, measured (2 shared cores): plate, H/Δx = 30,
11 191 particles — csph 7.3 kB, hpm 0.81 kB, sph 0.57 kB each; 3-D block of the SS curve, 13³
particles — csph 46.5 kB each; the largest (csph) is taken for every method, rounded up. FEM: not
measured, from the nonzeros of a quadratic element's tangent (2-D ~100, 3-D ~1 100 per node at 12
bytes) times a direct solver's fill-in (~15). An order of magnitude: it refuses a run that cannot
fit, not one that is merely tight."""


def machine_memory() -> int:
    """Physical memory this process may use, bytes: MemTotal of ``/proc/meminfo`` (else
    ``os.sysconf``), capped by a cgroup v2 limit (``/sys/fs/cgroup/memory.max``) where set."""
    import os

    total = 0
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal:"):
                total = int(line.split()[1]) * 1024
                break
    except OSError:
        pass
    if not total:
        try:
            total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        except (ValueError, OSError, AttributeError):
            total = 0
    try:
        limit = open("/sys/fs/cgroup/memory.max").read().strip()
        if limit.isdigit() and (not total or int(limit) < total):
            total = int(limit)
    except OSError:
        pass
    return total or 2 ** 62


def human_bytes(n: float) -> str:
    """``n`` bytes as '87 TiB', '7.3 GiB', '512 MiB'."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if abs(n) < 1024 or unit == "EiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024.0
    return f"{n:.3g} EiB"  # pragma: no cover


def estimate_points(scene, resolution: int, solver: str) -> tuple[float, int]:
    """(points, dim) of one run: particles of a particle method, nodes of the FEM (quadratic
    elements: 2r + 1 per edge), from the bounding boxes of the model's regions at the spacing
    ``length / resolution`` — without discretising anything."""
    model = scene.model()
    dx = model.length / float(resolution)
    try:
        model = scene.model(dx)
    except Exception:  # a model whose geometry cannot take this spacing: the plain one's extent
        pass
    per_length = (2.0 if solver == "fem" else 1.0) / dx
    points = 0.0
    for reg in model.regions:
        b = reg.shape.bounds() if hasattr(reg, "shape") else None
        if b is None:
            continue
        lo, hi = np.asarray(b[0], float), np.asarray(b[1], float)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            continue
        points += float(np.prod(np.maximum(hi - lo, 0.0) * per_length + 1.0))
    return points, int(model.dim)


def estimate_bytes(solver: str, scene, resolution: int) -> tuple[float, float, int]:
    """(bytes, points, bytes per point) one run of ``solver`` on ``scene`` at ``resolution``
    will need (:data:`BYTES_PER_POINT`)."""
    points, dim = estimate_points(scene, resolution, solver)
    per = BYTES_PER_POINT[dim]["fem" if solver == "fem" else "particle"]
    return points * per, points, per


def check_memory(solver: str, scene, resolution: int, available: int | None = None) -> None:
    """Refuse (:class:`~workbench.scenes.ParameterError`, one line) a run whose estimated memory
    (:func:`estimate_bytes`) exceeds this machine's (:func:`machine_memory`), naming both and the
    largest resolution that would fit."""
    from workbench.scenes import ParameterError

    if solver == "analytic":
        return
    need, points, per = estimate_bytes(solver, scene, resolution)
    have = machine_memory() if available is None else available
    if need <= have:
        return
    dim = estimate_points(scene, 1, solver)[1]
    r_max = int(resolution * (have / need) ** (1.0 / dim))
    while r_max > 1 and estimate_bytes(solver, scene, r_max)[0] > have:
        r_max -= max(1, r_max // 50)
    kind = "nodes" if solver == "fem" else "particles"
    raise ParameterError(
        f"resolution: {resolution} needs about {human_bytes(need)} for {scene.name} with {solver} "
        f"({points:.3g} {kind} x ~{human_bytes(per)} incl. neighbour lists); this machine has "
        f"{human_bytes(have)}; allowed: integers in [1, {max(r_max, 1)}] for {solver} here")


def validate(study, scene=None, solvers=None, resolutions=None, quick: bool = False):
    """Check a study's run before any work starts: the scene (its type and its model), the
    solvers, the resolutions (integers >= 1, not an empty list) and the memory each run will need.
    Returns (solvers, ladders) as :func:`ladders`; raises
    :class:`~workbench.scenes.ParameterError` (one line naming the parameter and its allowed
    range). Calls no solver: cheap enough to run on every input (the property tests do)."""
    from workbench.scenes import ParameterError, Scene

    scene_cls = getattr(study, "SCENE", None)
    if scene is None:
        if scene_cls is None:
            raise ParameterError(f"scene: {study.NAME} needs a scene; allowed: a Scene instance")
        scene = scene_cls()
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene: {scene!r} is not a Scene; allowed: a Scene instance")
    if quick and hasattr(study, "quick_scene"):  # the scene a quick run takes (a 2-D variant)
        scene = study.quick_scene(scene)
    if scene_cls is not None and study.NAME != "stability" and not isinstance(scene, scene_cls):
        raise ParameterError(f"scene: {type(scene).__name__} is not allowed for {study.NAME}; "
                             f"allowed: {scene_cls.__name__}")
    model = scene.model()  # SceneError (one line) where the parameters do not hold together
    allowed = tuple(getattr(study, "SOLVERS", None) or study.solvers_for(model))
    if isinstance(solvers, str):
        solvers = [solvers]
    solvers = list(solvers or allowed)
    for s in solvers:
        if s not in allowed:
            raise ParameterError(f"solver: {s!r} is not supported by {study.NAME}; allowed: "
                                 f"{', '.join(allowed)}")
    if isinstance(resolutions, dict):
        for s, lad in resolutions.items():
            check_resolutions(lad)
    elif resolutions is not None:
        check_resolutions(resolutions)
    if getattr(study, "NAME", "") == "scene":  # the generic study: one ladder for every solver
        default = study.QUICK_RESOLUTIONS if quick else study.RESOLUTIONS
        lads = {s: check_resolutions(resolutions.get(s, default) if isinstance(resolutions, dict)
                                     else (resolutions or default)) for s in solvers}
        kept = solvers
    elif isinstance(getattr(study, "RESOLUTIONS", None), dict):
        kept, lads = ladders(solvers, resolutions, study, quick, scene)
    else:  # a study with fixed resolutions of its own (stability)
        kept, lads = solvers, {}
    for s, lad in lads.items():
        for r in lad:
            check_memory(s, scene, r)
    return kept, lads



def ladders(solvers, resolutions, study, quick: bool, scene=None) -> tuple[list, dict]:
    """The solvers that run and each one's :func:`ladder`: a solver whose ladder is empty (a
    variant the quick ladder leaves out) is dropped; 'analytic' is kept (it has no ladder)."""
    lads = {s: ladder(s, resolutions, study, quick, scene) for s in solvers if s != "analytic"}
    kept = [s for s in solvers if s == "analytic" or lads[s]]
    return kept, {s: lads[s] for s in kept if s != "analytic"}


def ladder(solver: str, resolutions, study, quick: bool, scene=None) -> list[int]:
    """The resolutions ``solver`` runs at: ``resolutions`` may be None (the study's ladder, or its
    quick ladder; for ``scene``, where the study's ladder depends on it: its
    ``default_resolutions``), a list (every discrete solver but the FEM reference, which keeps its
    own), or a dict solver -> list."""
    table = study.QUICK_RESOLUTIONS if quick else study.RESOLUTIONS
    if scene is not None and hasattr(study, "default_resolutions"):
        table = study.default_resolutions(scene, quick)
    default = list(table.get(solver, ()))
    if resolutions is None:
        return default
    if isinstance(resolutions, dict):
        return check_resolutions(resolutions.get(solver, default))
    if solver == "fem" and study.NAME != "ss_curve":
        return default
    return check_resolutions(resolutions)


FIELD_SOLVERS = ("fem", "csph", "hpm", "sph")
"""The solvers that write fields (``fields=<folder>``): the particle methods their particles, the
FEM its mesh (the plate's dynamic run only)."""


def field_options(solver: str, resolution: int, fields, field_runs=None) -> dict:
    """The solver options asking one run for field output: ``{"fields": folder}`` when ``fields``
    (a folder) is given, ``solver`` writes fields, and (solver, resolution) is in ``field_runs``
    (None: every run); else ``{}``."""
    if fields is None or solver not in FIELD_SOLVERS:
        return {}
    if field_runs is not None and (solver, int(resolution)) not in set(field_runs):
        return {}
    return {"fields": str(fields)}


def field_series(scene, tasks) -> str:
    """The ``.pvd`` file names the ``tasks`` that asked for fields have written (those that exist),
    comma-separated, for the dataset's ``field_series`` attribute."""
    from pathlib import Path

    from workbench.fields import series_name

    names = []
    for t in tasks:
        folder = dict(t.options).get("fields")
        if folder is None:
            continue
        pvd = Path(folder) / f"{series_name(scene.name, t.solver, t.resolution)}.pvd"
        if pvd.exists():
            names.append(pvd.name)
    return ", ".join(names)
