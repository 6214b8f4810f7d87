"""Throughput of the particle methods' time loops on the plate scene (contract: ``bench.nc``).

:func:`particle_steps_per_second` builds the 2-D plate (004 D) at about ``n_particles`` particles,
runs a few steps to compile (JIT warm-up, not timed), then times the explicit time loop alone —
particles × steps / wall time. ``law='j2'`` swaps the plate's SVK rubber for the Table 1 steel
(J2, history per particle) on the same particles, for the plastic throughput.
"""
from __future__ import annotations

import math
import resource
import time

import numpy as np


def _rss_bytes() -> int:
    """Peak resident memory of this process so far, bytes (Linux ru_maxrss is in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def plate_resolution(n_particles: int) -> int:
    """Particles across H giving about ``n_particles`` on the node lattice of the default plate
    ((12 r + 1)(r + 1) particles including the clamp)."""
    r = max(2, int(round((-13 + math.sqrt(169 + 48 * (n_particles - 1))) / 24)))
    return r


def particle_steps_per_second(solver: str = "csph", n_particles: int = 100_000, threads: int = 1,
                              steps: int | None = None, law: str = "svk", min_time: float = 2.0) -> dict:
    """Time the plate's time loop of ``solver`` on ``threads`` numba threads.

    Returns dict(particle_steps_per_second, n_particles, steps, loop_time, threads,
    state_bytes_per_particle (the arrays the loop keeps: positions, velocities, neighbours,
    corrected gradients, stress, history), peak_rss_bytes_per_particle (the process's peak
    resident memory over N; includes the interpreter and the one-off neighbour search),
    setup_time, law)."""
    import numba

    if solver != "csph":
        raise ValueError(f"solver: {solver!r} is not benchmarked here; allowed: 'csph'")
    if not (isinstance(threads, int) and 1 <= threads <= numba.config.NUMBA_NUM_THREADS):
        raise ValueError(f"threads: {threads!r} is not allowed; 1..{numba.config.NUMBA_NUM_THREADS}")
    from workbench.analytic import plate_initial_velocity
    from workbench.materials import TABLE1_STEEL
    from workbench.scenes import Plate

    from . import csph, lattice
    from .integrate import cfl_time_step

    numba.set_num_threads(threads)
    scene = Plate()
    res = plate_resolution(int(n_particles))
    t0 = time.perf_counter()
    ps = lattice.plate(scene, res, mode="node")
    mat = scene.material if law == "svk" else TABLE1_STEEL
    if law not in ("svk", "j2"):
        raise ValueError(f"law: {law!r} is not one of 'svk', 'j2'")
    disc = csph.discretise(ps.X, ps.V, mat.rho, ps.dx, 1.1, "cubic_spline", csph.DEFAULT_CORRECTION)
    body = csph.Body(disc, mat)
    N = disc.n
    fixed = np.zeros((N, 2), np.uint8)
    fixed[ps.sets["fixed"]] = 1
    v0 = np.zeros((N, 2))
    v0[:, 1] = plate_initial_velocity(scene, disc.X[:, 0])
    if law == "j2":
        v0 *= 5.0  # enough velocity to yield the root of the steel plate within the run
    dt = cfl_time_step(ps.dx, mat.wave_speed("strain"), scene.dt_factor)
    dyn = csph.Dynamics(body, v0, fixed, dt)
    setup = time.perf_counter() - t0
    dyn.advance(2)  # JIT warm-up (compiled code from the cache when warm)
    n = steps or max(10, int(2e6 / N))
    total, loop = 0, 0.0
    while loop < min_time or total == 0:
        tl = time.perf_counter()
        _, bad = dyn.advance(n)
        loop += time.perf_counter() - tl
        total += n
        if steps:
            break
    state = disc.nbytes() + sum(a.nbytes for a in (dyn.x, dyn.v, dyn.acc, dyn.fixed, dyn.v_fix,
                                                    dyn.f_ext, body.VP, body.history,
                                                    dyn.h_scratch, body.status))
    return dict(particle_steps_per_second=N * total / loop, n_particles=N, steps=total,
                loop_time=loop, threads=threads, law=law,
                state_bytes_per_particle=state / N, peak_rss_bytes_per_particle=_rss_bytes() / N,
                setup_time=setup, numba_threading_layer=numba.threading_layer(),
                status="ok" if bad < 0 else f"unstable: material point failed at step {bad}")


if __name__ == "__main__":  # python -m sph.bench [N] [threads]
    import sys

    N = int(float(sys.argv[1])) if len(sys.argv) > 1 else 100_000
    th = [int(t) for t in sys.argv[2:]] or [1]
    for t in th:
        for law in ("svk", "j2"):
            r = particle_steps_per_second("csph", N, t, law=law)
            print({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()}, flush=True)
