"""Benchmark of the FEM reference (not a test): ``python -m fem_reference.bench [--quick]``.

Prints, on this machine:

1. DOFs, material update + assembly time and linear-solve time of one Newton iteration of the
   plane-strain cantilever (biquadratic quadrilaterals) at several resolutions;
2. the time to the plate's modal period converged to 0.1 %: a ladder of resolutions 2, 4, 8, …,
   stopped when the Richardson estimate of the error of the last level (observed order from the
   last three levels) is below 0.1 %; also the single run at that resolution;
3. the large-deflection cantilever (the scene's loads up to P L²/(E I) = 5) at about 10⁵ DOFs.

Timings are wall-clock with numba's cache warm (a small run first) and the CPU count printed.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import platform
import time

import numpy as np


def newton_iteration_cost(resolutions) -> list[dict]:
    from workbench.scenes import Cantilever

    from .model import build
    from workbench.linear_systems import direct_solve

    rows = []
    for n in resolutions:
        problem = build(Cantilever(), n).problem
        disc = problem.disc
        st = problem.initial_state()
        u = np.zeros(disc.N)
        u[disc.free] = 1e-6 * np.sin(np.arange(len(disc.free)))  # a deformed state
        problem.evaluate(u, st)  # JIT and the sparsity pattern out of the timing
        disc.tangent(problem.evaluate(u, st)["A"])
        reps = 3 if disc.N < 50000 else 1
        t0 = time.perf_counter()
        for _ in range(reps):
            pt = problem.evaluate(u, st, tangent=True)
        t_mat = (time.perf_counter() - t0) / reps
        t0 = time.perf_counter()
        for _ in range(reps):
            K = disc.tangent(pt["A"])
        t_asm = (time.perf_counter() - t0) / reps
        t0 = time.perf_counter()
        for _ in range(reps):
            direct_solve(K, -pt["f_int"][disc.free] + 1.0)
        t_sol = (time.perf_counter() - t0) / reps
        rows.append(dict(resolution=n, n_dof=disc.N, material_and_residual=t_mat,
                         tangent_assembly=t_asm, solve=t_sol))
    return rows


def plate_modal_to_tolerance(tol: float = 1e-3) -> dict:
    from workbench.scenes import Plate

    from .model import solve

    t0 = time.perf_counter()
    ns, T, times = [], [], []
    n = 2
    while True:
        r = solve(Plate(), n, dynamic=False)
        ns.append(n)
        T.append(r["period"])
        times.append(r["wall_time"])
        if len(T) >= 3:
            d1, d2 = T[-2] - T[-3], T[-1] - T[-2]
            p = math.log(abs(d1 / d2)) / math.log(2) if d1 * d2 > 0 else 1.0
            est = abs(d2) / (2 ** p - 1)
            if est / T[-1] < tol:
                break
        n *= 2
    return dict(resolutions=ns, periods=T, order=p, error_estimate=est / T[-1],
                ladder_time=time.perf_counter() - t0, last_run_time=times[-1],
                n_dof=r["n_dof"], extrapolated=T[-1] + math.copysign(est, T[-1] - T[-2]))


def large_cantilever(resolution: int) -> dict:
    from workbench import analytic
    from workbench.scenes import Cantilever

    from .model import solve

    sc = Cantilever()
    t0 = time.perf_counter()
    r = solve(sc, resolution)
    r["total_time"] = time.perf_counter() - t0
    r["elastica"] = [analytic.cantilever_elastica(sc, p)[0] for p in sc.loads]
    return r


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes only (seconds)")
    ap.add_argument("--large", type=int, default=40,
                    help="elements across H of the large cantilever (40: 103 842 DOFs)")
    args = ap.parse_args(argv)
    import numba

    print(f"# fem_reference bench — {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, numba threads {numba.get_num_threads()}, "
          f"load average {os.getloadavg()[0]:.1f} at start")
    from workbench.scenes import Cantilever

    from .model import solve

    solve(dataclasses.replace(Cantilever(), loads=(0.5,)), 1)  # warm numba's cache

    print("\n## one Newton iteration, plane-strain cantilever, Q2 (9-node) quadrilaterals")
    print(f"{'n_H':>4} {'DOFs':>8} {'material+f_int s':>17} {'tangent s':>10} {'solve s':>9}")
    for row in newton_iteration_cost([2, 4, 8] if args.quick else [4, 10, 20, 40]):
        print(f"{row['resolution']:>4} {row['n_dof']:>8} {row['material_and_residual']:>17.4f} "
              f"{row['tangent_assembly']:>10.4f} {row['solve']:>9.4f}")

    print("\n## plate modal period to 0.1 %")
    m = plate_modal_to_tolerance(1e-3)
    for n, T in zip(m["resolutions"], m["periods"]):
        print(f"  n_H = {n:>3}: T = {T:.6f} s")
    print(f"  observed order {m['order']:.2f}, estimated error of the last level "
          f"{100 * m['error_estimate']:.3f} %, extrapolated T = {m['extrapolated']:.6f} s")
    print(f"  ladder time {m['ladder_time']:.2f} s; the last run alone ({m['n_dof']} DOFs) "
          f"{m['last_run_time']:.2f} s")

    if args.quick:
        return
    print(f"\n## large-deflection cantilever, n_H = {args.large}")
    r = large_cantilever(args.large)
    print(f"  DOFs {r['n_dof']}, status {r['status']}")
    for k, p in enumerate(r["load"]):
        print(f"  P L²/(E I) = {p:<8g} v/L = {r['tip_deflection'][k] / 0.16:.6f} "
              f"(elastica {r['elastica'][k] / 0.16:.6f})  Newton iterations "
              f"{r['newton_iterations'][k]}  cumulative {r['wall_time'][k]:.1f} s "
              f"(material+assembly {r['assembly_time'][k]:.1f} s, solve {r['solve_time'][k]:.1f} s)")
    print(f"  total {r['total_time']:.1f} s; {r['factorisations']} LU factorisations, "
          f"{r['krylov_iterations']} preconditioned GMRES iterations")


if __name__ == "__main__":
    main()
