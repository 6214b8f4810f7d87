"""The benchmark study: throughput of the particle methods' time loops (contract: ``bench.nc``;
``workbench bench [--scene S]``).

:func:`particle_steps_per_second` builds a scene's body at about ``n_particles`` particles the way
the driver does (:func:`scene_body`: model → particles → the method's build → loads, constraints,
contact), runs two steps to compile (JIT warm-up, not timed), then times the method's time loop
alone — particles × steps / wall time. The scenes (:data:`SCENES`):

* ``plate`` (the default): the 2-D plate (004 D), SVK rubber; ``law='j2'`` swaps it for the
  Table 1 steel (J2, history per particle) on the same particles, for the plastic throughput;
* ``microcantilever3d``: the 3-D micro-cantilever of paper 000 (J2 grains and grain boundaries,
  :class:`studies.microcantilever.scene.MicroCantilever`, ``dim=3``), csph with the study's 3-D options;
* ``rc_beam``: the reinforced mortar beam of paper 003 (:class:`studies.rc_beam.scene.RCBeam`, specimen
  A, quarter model: the mortar law, J2 bars, the weight and supports in contact), sph and csph with
  the rc_beam study's options (classic SPH's list with its skin; ``sph_every_step`` searching
  every step, :data:`VARIANTS`; with contact both run the driver's generic step loop).

Each measurement runs in a fresh subprocess (``python -m studies.bench``), so that its peak memory
is its own.
"""
from __future__ import annotations

import math
import resource
import time
from dataclasses import dataclass

import numpy as np


def _rss_bytes() -> int:
    """Peak resident memory of this process so far, bytes (Linux ru_maxrss is in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def plate_resolution(n_particles: int) -> int:
    """Particles across H giving about ``n_particles`` on the node lattice of the default plate
    ((12 r + 1)(r + 1) particles including the clamp)."""
    r = max(2, int(round((-13 + math.sqrt(169 + 48 * (n_particles - 1))) / 24)))
    return r


def plate_body(solver: str, n_particles: int, law: str = "svk", **options):
    """The plate scene's body of ``solver`` at about ``n_particles`` particles, set up exactly as
    the driver sets it up (model → particles → the method's build → loads and constraints) and
    started: returns (body, dt, fixed (N, d) uint8, f_ext, v_fix, setup time). ``law='j2'`` swaps
    the rubber for the Table 1 steel (J2, history per particle) on the same particles and raises
    the initial velocity five-fold, so that the root of the plate yields within a short run."""
    sb = scene_body("plate", solver, n_particles, law, **options)
    return sb.body, sb.dt, sb.fixed, sb.f_ext, sb.v_fix, sb.setup_time


LATTICE = {"sph": "cell"}
"""The plate's lattice per method (classic SPH on the cell lattice, as in the plate study)."""

SCENES = ("plate", "microcantilever3d", "rc_beam")
SCENE_SOLVERS = {"plate": ("csph", "hpm", "sph"), "microcantilever3d": ("csph",),
                 "rc_beam": ("sph", "sph_every_step", "csph")}
"""The methods benchmarked on each scene (those its study runs, and :data:`VARIANTS`)."""
VARIANTS = {"sph_every_step": ("sph", dict(skin=0.0))}
"""Benchmark-only variants: name -> (method, options over the study's). ``sph_every_step``:
classic SPH with its neighbours searched every step (``skin`` 0), 003's Fig. 6 step as issue 12's
benchmark names it; the study's ``sph`` searches again only once a particle has moved half its
skin, with the same pairs in every step."""
SCENE_PARTICLES = {"plate": (10_000, 100_000), "microcantilever3d": (100_000,),
                   "rc_beam": (15_000,)}
"""Default requested particles per scene: rc_beam's is the paper's 5 mm quarter model (specimen A,
15 496 particles); the micro-cantilever's the ~1e5 of issue 11."""
PROBE_RESOLUTION = {"microcantilever3d": 10, "rc_beam": 8}
"""The resolution whose particle count scales to the requested one (:func:`resolution_for`)."""


@dataclass
class SceneBody:
    """A started body and what its time loop needs (:func:`scene_body`)."""
    body: object
    dt: float
    fixed: np.ndarray  # (N, d) uint8
    f_ext: np.ndarray  # (N, d) dead loads, N
    v_fix: np.ndarray  # (N, d) velocity of the fixed DOFs, m/s
    extra: object  # contact force callable(x) -> (N, d), or None
    damping: float  # mass-proportional, 1/s
    resolution: int
    law: str  # the material law(s) of the body, for the record
    setup_time: float  # s


def scene_of(name: str):
    """The scene object of a benchmark scene name (:data:`SCENES`)."""
    from workbench.scenes import Plate

    from .microcantilever.scene import MicroCantilever
    from .rc_beam.scene import RCBeam

    if name == "plate":
        return Plate()
    if name == "microcantilever3d":
        return MicroCantilever(dim=3)
    if name == "rc_beam":
        return RCBeam()
    raise ValueError(f"scene: {name!r} is not one of {', '.join(SCENES)}")


def scene_options(name: str, solver: str) -> dict:
    """The method options the scene's study runs with (the micro-cantilever's 3-D csph options,
    the rc_beam study's per-solver options); none for the plate. A variant
    (:data:`VARIANTS`): its method's, with its own options over them."""
    if solver in VARIANTS:
        method, extra = VARIANTS[solver]
        return {**scene_options(name, method), **extra}
    if name == "microcantilever3d" and solver == "csph":
        from .microcantilever.ladders import OPTIONS_3D

        return dict(OPTIONS_3D)
    if name == "rc_beam":
        from .rc_beam.ladders import OPTIONS

        return dict(OPTIONS.get(solver, {}))
    return {}


def smallest_resolution(name: str, scene) -> int:
    """The coarsest resolution the scene allows: the micro-cantilever's grain boundaries hold a
    particle (H/Δx ≥ H/gb_thickness); 1 for the others."""
    if name == "microcantilever3d":
        return math.ceil(scene.H / scene.gb_thickness - 1e-9)
    return 1


def resolution_for(name: str, scene, n_particles: int) -> int:
    """The resolution giving about ``n_particles``: the plate's closed form
    (:func:`plate_resolution`), else the particle count at :data:`PROBE_RESOLUTION` scaled by
    (N/N_probe)^(1/dim), corrected once more from the count at that resolution (the parts made of
    whole layers — rc_beam's weight, plate and supports — do not scale as r^dim), and at least
    :func:`smallest_resolution`."""
    from sph import driver, particles

    if name == "plate":
        return plate_resolution(n_particles)
    r = PROBE_RESOLUTION[name]
    for _ in range(2):
        model, _ = driver.model_at(scene, r)
        n = particles.discretise(model, r).n
        r_next = max(smallest_resolution(name, scene),
                     int(round(r * (n_particles / n) ** (1.0 / model.dim))))
        if r_next == r:
            break
        r = r_next
    return r


def scene_body(name: str, solver: str, n_particles: int, law: str | None = None,
               **options) -> SceneBody:
    """The body of ``solver`` on the benchmark scene ``name`` at about ``n_particles`` particles,
    set up as :func:`sph.driver.solve` sets up an explicit run (model → particles → the method's
    build with the scene's options (:func:`scene_options`) and ``options`` → time step (the
    drive's ``dt_factor`` and reference), dead loads, prescribed velocity at t = 0, contact) and
    started. ``law``: the plate's 'svk' (its default) or 'j2' (the Table 1 steel on the same
    particles, initial velocity five-fold, so that the root yields within a short run); the other
    scenes keep their own materials (``law`` None)."""
    import dataclasses

    from sph import driver, particles
    from workbench.materials import TABLE1_STEEL

    if name not in SCENES:
        raise ValueError(f"scene: {name!r} is not one of {', '.join(SCENES)}")
    if name == "plate":
        law = law or "svk"
        if law not in ("svk", "j2"):
            raise ValueError(f"law: {law!r} is not one of 'svk', 'j2'")
    elif law is not None:
        raise ValueError(f"law: {law!r} is not allowed on {name}; allowed: None (the scene's own)")
    t0 = time.perf_counter()
    scene = scene_of(name)
    res = resolution_for(name, scene, int(n_particles))
    model, _ = driver.model_at(scene, res)
    if law == "j2":
        model = dataclasses.replace(model, regions=tuple(dataclasses.replace(r, material=TABLE1_STEEL)
                                                         for r in model.regions))
    ps = particles.discretise(model, res, LATTICE.get(solver) if name == "plate" else None)
    mod, defaults = driver.method_entry(VARIANTS.get(solver, (solver,))[0])
    body = mod.build(ps, **{**defaults, **scene_options(name, solver), **options})
    run = driver.Run(model, ps, body)
    drive = model.drive
    dt, fixed, f_ext, v_fix, extra, _ = run.start_explicit(5.0 if law == "j2" else 1.0)
    laws = sorted({r.material.law for r in model.regions})
    return SceneBody(body, dt, fixed, f_ext, v_fix, extra, float(getattr(drive, "damping", 0.0)),
                     res, law or "+".join(laws), time.perf_counter() - t0)


def particle_steps_per_second(solver: str = "csph", n_particles: int = 100_000, threads: int = 1,
                              steps: int | None = None, law: str | None = None,
                              min_time: float = 2.0, scene: str = "plate") -> dict:
    """Time the time loop of ``solver`` on the benchmark ``scene`` (:func:`scene_body`; its
    ``advance``: the fused compiled loop, or with contact the generic step loop) on ``threads``
    numba threads, after two warm-up steps (JIT from the cache). Without ``steps``: one step to
    gauge the step's cost, then chunks until ``min_time`` seconds of loop.

    Returns dict(particle_steps_per_second, n_particles, steps, loop_time, threads, law, scene,
    resolution, peak_rss_bytes_per_particle (the process's peak resident memory over N; includes
    the interpreter and the one-off neighbour search), setup_time, status)."""
    import numba

    from sph import METHODS

    if solver not in METHODS and solver not in VARIANTS:
        raise ValueError(f"solver: {solver!r} is not a particle method; allowed: "
                         f"{', '.join((*METHODS, *VARIANTS))}")
    if not (isinstance(threads, int) and 1 <= threads <= numba.config.NUMBA_NUM_THREADS):
        raise ValueError(f"threads: {threads!r} is not allowed; 1..{numba.config.NUMBA_NUM_THREADS}")
    numba.set_num_threads(threads)
    sb = scene_body(scene, solver, n_particles, law)
    body = sb.body
    N = body.n

    def advance(k):
        return body.advance(k, sb.dt, sb.f_ext, sb.fixed, sb.v_fix, sb.damping, sb.extra)

    done = n = advance(2)  # JIT warm-up (compiled code from the cache when warm)
    total, loop = 0, 0.0
    while done == n:
        n = steps or (1 if total == 0 else  # the first step gauges the cost of one
                      max(1, min(4 * total, int(math.ceil((min_time - loop) * total / loop)))))
        tl = time.perf_counter()
        done = advance(n)
        loop += time.perf_counter() - tl
        total += done
        if steps or loop >= min_time:
            break
    return dict(particle_steps_per_second=N * total / loop, n_particles=N, steps=total,
                loop_time=loop, threads=threads, law=sb.law, scene=scene, resolution=sb.resolution,
                peak_rss_bytes_per_particle=_rss_bytes() / N, setup_time=sb.setup_time,
                status="ok" if done == n else f"unstable: material point failed after {total} steps")


# --------------------------------------------------------------------------------------------------
# ``workbench bench``: the sweep, each measurement in its own subprocess
# (``python -m studies.bench --one``)

SOLVERS = SCENE_SOLVERS["plate"]
DEFAULT_PARTICLES = SCENE_PARTICLES["plate"]
PARTICLES_RANGE = (100, 10_000_000)
REPEATS_ENV = "WORKBENCH_BENCH_REPEATS"  # fresh subprocesses per measurement, best kept (default 3)
TIMEOUT_ENV = "WORKBENCH_BENCH_TIMEOUT"  # seconds per measurement, overriding :func:`_timeout`
STARTUP_COLD_TIMEOUT = 900.0  # the first (cache-filling) start-up run may compile everything


def _current_rss_bytes() -> int:
    """Resident memory of this process now, bytes."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * resource.getpagesize()
    except (OSError, IndexError, ValueError):  # pragma: no cover - not Linux
        return _rss_bytes()


def _machine_cores() -> int:
    try:
        import os

        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover
        import os

        return os.cpu_count() or 1


def _timeout(n_particles: int, scene: str = "plate") -> float:
    """Wall-clock limit of one measurement subprocess, s (setup, warm-up and the timed loop); the
    3-D scenes' set-up (neighbours, corrections, contact) costs about ten times the plate's per
    particle."""
    import os

    env = os.environ.get(TIMEOUT_ENV)
    if env:
        return float(env)
    return 120.0 + (3e-3 if scene == "plate" else 3e-2) * n_particles


def _run_solver(solver: str, n_particles: int, threads: int, steps: int | None = None,
                scene: str = "plate") -> dict:
    """:func:`particle_steps_per_second` with the threading layer noted."""
    import numba

    out = dict(particle_steps_per_second(solver, n_particles, threads, steps=steps, scene=scene))
    out.setdefault("status", "ok")
    try:
        out.setdefault("numba_threading_layer", numba.threading_layer())
    except ValueError:  # no parallel region ran
        out.setdefault("numba_threading_layer", "none")
    return out


def _child_measure(solver: str, n_particles: int, threads: int, scene: str = "plate") -> dict:
    """Body of ``python -m studies.bench --one``: import, note the baseline memory, run, report."""
    import numba

    from sph import classic, csph, driver, hpm  # noqa: F401  (imports belong to the baseline)
    from workbench import analytic, scenes  # noqa: F401

    baseline = _current_rss_bytes()
    out = _run_solver(solver, n_particles, threads, scene=scene)
    peak = _rss_bytes()
    n = int(out["n_particles"])
    out.update(peak_rss_bytes=peak, baseline_rss_bytes=baseline, bytes_per_particle=peak / n,
               incremental_bytes_per_particle=(peak - baseline) / n, numba_version=numba.__version__)
    return out


def _child_startup(solver: str, n_particles: int, scene: str = "plate") -> dict:
    """Body of ``python -m studies.bench --startup``: the scene set up and one step taken (after
    the solver's two warm-up steps, at a small N negligible), then the wall-clock time."""
    out = _run_solver(solver, n_particles, 1, steps=1, scene=scene)
    return dict(first_step_done=time.time(), n_particles=out["n_particles"], status=out["status"])


def _subprocess(argv: list[str], timeout: float) -> tuple[dict | None, str]:
    """Run ``python -m studies.bench ARGV``; return (the JSON it printed last, status)."""
    import json
    import subprocess
    import sys

    try:
        proc = subprocess.run([sys.executable, "-m", "studies.bench", *argv], capture_output=True,
                              text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, f"error: timed out after {timeout:.0f} s"
    for line in reversed(proc.stdout.strip().splitlines()):
        if line.startswith("{"):
            try:
                return json.loads(line), "ok"
            except ValueError:
                break
    lines = [ln for ln in proc.stderr.strip().splitlines() if ln.strip()]
    why = lines[-1].strip() if lines else f"exit status {proc.returncode}"
    return None, f"error: {why}"[:300]


def measure(solver: str, n_particles: int, threads: int, timeout: float | None = None,
            scene: str = "plate") -> dict:
    """One (solver, particles, threads) measurement on ``scene`` in a fresh subprocess, so that
    its peak memory is its own and a hang costs at most ``timeout`` seconds. Never raises: a
    failure is dict(status='error: …')."""
    t = _timeout(n_particles, scene) if timeout is None else timeout
    out, status = _subprocess(["--one", solver, str(n_particles), str(threads), scene], t)
    if out is None:
        return {"status": status}
    return out


def startup_time(solver: str, n_particles: int, timeout: float | None = None,
                 scene: str = "plate") -> dict:
    """Seconds from launching a fresh interpreter to the end of the scene's first step with
    numba's cache warm: launched twice, the first run fills the cache, the second counts."""
    t = _timeout(n_particles, scene) if timeout is None else timeout
    cold = max(t, STARTUP_COLD_TIMEOUT) if timeout is None else timeout  # an explicit limit holds for both
    res = {}
    for attempt, limit in (("cold", cold), ("warm", t)):
        t0 = time.time()
        out, status = _subprocess(["--startup", solver, str(n_particles), scene], limit)
        if out is None:
            return {"startup_time": math.nan, "status": f"{status} ({attempt} start)"}
        res[attempt] = out["first_step_done"] - t0
    return {"startup_time": res["warm"], "cold_startup_time": res["cold"], "status": "ok"}


class UsageError(ValueError):
    """A bad ``workbench bench`` argument (the CLI prints it as one line, exit status 2)."""


def _validate(args) -> tuple[str, list[str], list[int], list[int]]:
    cores = _machine_cores()
    scene = getattr(args, "scene", None) or "plate"
    if scene not in SCENES:
        raise UsageError(f"--scene: {scene!r} is not benchmarked; allowed: {', '.join(SCENES)}")
    allowed = SCENE_SOLVERS[scene]
    solvers = list(dict.fromkeys(args.solver or allowed))
    for s in solvers:
        if s not in allowed:
            raise UsageError(f"--solver: {s!r} is not benchmarked on {scene}; allowed: "
                             f"{', '.join(allowed)}")
    particles = sorted(set(args.particles or SCENE_PARTICLES[scene]))
    lo, hi = PARTICLES_RANGE
    for n in particles:
        if not lo <= n <= hi:
            raise UsageError(f"--particles: {n} is out of range; allowed: {lo}..{hi}")
    if args.threads:
        threads = sorted(set(args.threads))
        for t in threads:
            if not 1 <= t <= cores:
                raise UsageError(f"--threads: {t} is out of range; allowed: 1..{cores} "
                                 f"(this machine's cores)")
    else:
        threads = sorted({t for t in (1, 2) if t <= cores})
    return scene, solvers, particles, threads


def _load_average() -> str:
    try:
        import os

        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover
        return "unknown"


def main(args) -> int:
    """``workbench bench [--scene S]``: time each (solver, particles, threads) of the scene in a
    subprocess, write ``OUT/bench.nc`` (the scene, its laws and resolution in the attributes and
    ``resolution``) and ``OUT/bench.png``, print a table. Exit status 0 (also when some runs
    failed: a failure is a recorded result); usage errors raise :class:`UsageError`."""
    import os
    from pathlib import Path

    import numba
    import xarray as xr

    from workbench import results

    scene, solvers, particles, threads = _validate(args)
    repeats = max(1, int(os.environ.get(REPEATS_ENV, "3")))
    out_dir = Path(args.out or "results")
    load_before = _load_average()
    shape = (len(solvers), len(particles), len(threads))
    psps = np.full(shape, np.nan)
    loop_time = np.full(shape, np.nan)
    steps = np.full(shape, np.nan)
    status = np.full(shape, "", dtype=object)
    bpp = np.full(shape[:2], np.nan)
    inc = np.full(shape[:2], np.nan)
    median = np.full(shape, np.nan)
    load1 = np.full(shape, np.nan)
    state = np.full(shape[:2], np.nan)
    n_actual = np.full(shape[:2], np.nan)
    resolution = np.full(shape[:2], np.nan)
    laws: set[str] = set()
    startup = np.full(len(solvers), np.nan)
    cold = np.full(len(solvers), np.nan)
    startup_status = np.full(len(solvers), "", dtype=object)
    layers: set[str] = set()
    n_start = particles[0]
    for i, s in enumerate(solvers):
        r = startup_time(s, n_start, scene=scene)  # also fills numba's cache before the timed runs
        startup[i], cold[i] = r["startup_time"], r.get("cold_startup_time", math.nan)
        startup_status[i] = r["status"]
        print(f"bench: {s} start-up {startup[i]:.2f} s (cold {cold[i]:.1f} s) {r['status']}", flush=True)
        for j, n in enumerate(particles):
            for k, t in enumerate(threads):
                load1[i, j, k] = os.getloadavg()[0]
                runs = [measure(s, n, t, scene=scene) for _ in range(repeats)]
                good = [x for x in runs if x.get("status") == "ok"]
                r = max(good, key=lambda x: x["particle_steps_per_second"]) if good else runs[0]
                if good:
                    median[i, j, k] = float(np.median([x["particle_steps_per_second"] for x in good]))
                st = str(r.get("status", "error: no status"))
                status[i, j, k] = st
                if "n_particles" in r:
                    n_actual[i, j] = r["n_particles"]
                    resolution[i, j] = r.get("resolution", math.nan)
                    laws.add(str(r.get("law", "")))
                if r.get("numba_threading_layer"):
                    layers.add(str(r["numba_threading_layer"]))
                if st == "ok":
                    psps[i, j, k] = r["particle_steps_per_second"]
                    loop_time[i, j, k] = r["loop_time"]
                    steps[i, j, k] = r["steps"]
                    # the fewest threads' run: the least thread-stack overhead in the peak
                    if np.isnan(bpp[i, j]):
                        bpp[i, j] = r["bytes_per_particle"]
                        inc[i, j] = r["incremental_bytes_per_particle"]
                        state[i, j] = r.get("state_bytes_per_particle", math.nan)
                print(f"bench: {s} N={n} threads={t}: {psps[i, j, k]:.3g} particle-steps/s  {st}",
                      flush=True)
    try:
        layer = numba.threading_layer()
    except ValueError:
        layer = ", ".join(sorted(layers)) or "unknown"
    extra = {"bench_scene": scene, "bench_laws": ", ".join(sorted(x for x in laws if x)),
             "bench_options": "; ".join(f"{s}: {scene_options(scene, s)}" for s in solvers),
             "numba_version": numba.__version__, "numba_threading_layer": layer,
             "machine_cores": _machine_cores(), "repeats": repeats,
             "particle_steps_per_second_definition": "best of `repeats` fresh subprocesses (a "
                                                     "shared machine only ever slows a run down)",
             "startup_particles": n_start,
             "load_average_before": load_before, "load_average_after": _load_average(),
             "timeout_per_measurement_s": ", ".join(f"{n}: {_timeout(n, scene):.0f}"
                                                    for n in particles),
             "startup_definition": "wall time from launching a fresh interpreter to the end of the "
                                   "scene's first step (after the solver's warm-up steps) at "
                                   "startup_particles, numba cache warm (second of two launches)",
             "bytes_per_particle_definition": "peak RSS (ru_maxrss) of a fresh subprocess running the "
                                              "fewest-threads measurement, over its particle count"}
    dims3, dims2 = ("solver", "particles", "threads"), ("solver", "particles")
    ds = xr.Dataset(
        {"particle_steps_per_second": (dims3, psps, {"units": "1/s", "long_name":
                                                     "particles x steps / wall time of the time loop"}),
         "particle_steps_per_second_median": (dims3, median, {"units": "1/s", "long_name":
                                                               "median over the repeats"}),
         "load_average": (dims3, load1, {"units": "-", "long_name":
                                         "1-minute load average before the measurement"}),
         "loop_time": (dims3, loop_time, {"units": "s"}),
         "steps": (dims3, steps, {"units": "-"}),
         "status": (dims3, status.astype(str), {"units": "-"}),
         "bytes_per_particle": (dims2, bpp, {"units": "B", "long_name":
                                             "peak resident memory of the run / particles"}),
         "incremental_bytes_per_particle": (dims2, inc, {"units": "B", "long_name":
                                                         "(peak RSS - RSS after imports) / particles"}),
         "state_bytes_per_particle": (dims2, state, {"units": "B", "long_name":
                                                     "arrays the time loop keeps / particles "
                                                     "(where the solver reports it)"}),
         "n_particles_actual": (dims2, n_actual, {"units": "-"}),
         "resolution": (dims2, resolution, {"units": "-", "long_name":
                                            "intervals across the scene's length scale (spacing length/r)"}),
         "startup_time": (("solver",), startup, {"units": "s"}),
         "cold_startup_time": (("solver",), cold, {"units": "s", "long_name":
                                                   "first launch (cache filled or reused)"}),
         "startup_status": (("solver",), startup_status.astype(str), {"units": "-"})},
        coords={"solver": ("solver", np.array(solvers)),
                "particles": ("particles", np.array(particles), {"units": "-", "long_name":
                                                                 "requested particles"}),
                "threads": ("threads", np.array(threads), {"units": "-"})},
        attrs=results.provenance("bench", scene_of(scene), extra))
    path = results.write(ds, out_dir / "bench.nc")
    png = plot(ds, out_dir / "bench.png")
    _print_table(ds)
    print(f"bench: {path}  {png}")
    return 0


def _print_table(ds) -> None:
    print(f"{'solver':<6} {'N req':>9} {'N':>9} {'thr':>3} {'particle-steps/s':>17} "
          f"{'B/particle':>11} {'startup s':>9}  status")
    for s in ds.solver.values:
        for n in ds.particles.values:
            for t in ds.threads.values:
                c = dict(solver=s, particles=n, threads=t)
                na = float(ds.n_particles_actual.sel(solver=s, particles=n))
                print(f"{s:<6} {int(n):>9} {('-' if math.isnan(na) else int(na)):>9} {int(t):>3} "
                      f"{float(ds.particle_steps_per_second.sel(c)):>17.3e} "
                      f"{float(ds.bytes_per_particle.sel(solver=s, particles=n)):>11.0f} "
                      f"{float(ds.startup_time.sel(solver=s)):>9.2f}  {str(ds.status.sel(c).values)}")


def plot(ds, path):
    """Particle-steps per second against particles, log-log, one line per solver x threads."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"csph": "tab:red", "hpm": "tab:green", "sph": "tab:purple"}
    styles = ["-", "--", ":", "-."]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for s in ds.solver.values:
        for k, t in enumerate(ds.threads.values):
            y = ds.particle_steps_per_second.sel(solver=s, threads=t).values
            x = ds.n_particles_actual.sel(solver=s).values
            x = np.where(np.isnan(x), ds.particles.values, x)
            ax.plot(x, y, marker="o", ls=styles[k % len(styles)], color=colours.get(str(s)),
                    label=f"{s}, {int(t)} thread{'s' if t > 1 else ''}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("particles N [-]")
    ax.set_ylabel("throughput [particle-steps / s]")
    ax.set_title(f"{ds.attrs.get('bench_scene', 'plate')} time loop, "
                 f"{ds.attrs.get('cpu_model', '')}"[:70], fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    from .figures import save

    return save(fig, path)


def _cli(argv: list[str]) -> int:
    """``python -m studies.bench --one SOLVER N THREADS [SCENE]`` / ``--startup SOLVER N [SCENE]``
    (one JSON line), or ``python -m studies.bench [N] [threads…]`` (plate, csph, SVK and J2)."""
    import json

    if argv and argv[0] == "--one":
        solver, n, t = argv[1], int(float(argv[2])), int(argv[3])
        scene = argv[4] if len(argv) > 4 else "plate"
        print(json.dumps(_child_measure(solver, n, t, scene), default=str), flush=True)
        return 0
    if argv and argv[0] == "--startup":
        scene = argv[3] if len(argv) > 3 else "plate"
        print(json.dumps(_child_startup(argv[1], int(float(argv[2])), scene), default=str),
              flush=True)
        return 0
    N = int(float(argv[0])) if argv else 100_000
    th = [int(t) for t in argv[1:]] or [1]
    for t in th:
        for law in ("svk", "j2"):
            r = particle_steps_per_second("csph", N, t, law=law)
            print({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()}, flush=True)
    return 0


if __name__ == "__main__":  # python -m studies.bench --one … | --startup … | [N] [threads…]
    import sys

    sys.exit(_cli(sys.argv[1:]))
