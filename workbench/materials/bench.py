"""Single-thread speed of the finite-strain J2 material point, in points per second.

Four cases, each a batch of ``n`` points through :func:`kernels.j2_point` in a serial compiled
loop (one thread; P and the history written to their rows, the tangent to one reused
(3, 3, 3, 3) block as an assembly loop would consume it, so that the timing is the point routine's
and not the memory traffic of an (n, 81) array). Times are the thread's CPU time (best of
``repeat``), which other jobs on a shared machine disturb less than wall time:

* ``elastic``: trial states inside the yield surface (rotated small strains, virgin history);
* ``plastic``: a further step of 5e-4 along a proportional path from ε ≈ 0.02, every point yields;
* ``elastic+tangent`` and ``plastic+tangent``: the same with the consistent tangent.

``--baseline REV`` times the kernels of a git revision in the same run (its
``workbench/materials`` modules are read with ``git show`` into a temporary package, see
:func:`load_baseline`), so that the ratio of the two is measured under the same load of a shared
machine (the two alternate within each round). The baseline gets the leading columns of its own
layout (its ``N_PARAMS`` and ``N_HISTORY_J2``; revisions up to 23e34f0, without them, had 10
parameters and 11 J2 history columns).

    python3 -m workbench.materials.bench --baseline afbb777
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from numba import njit

from . import TABLE1_STEEL, HIST_EPS_P, kernels
from .kernels import JIT

BASELINE_N_PARAMS = 10
BASELINE_N_HISTORY = 11
CASES = ("elastic", "plastic", "elastic+tangent", "plastic+tangent")


def _rotations(rng, n):
    Q, R = np.linalg.qr(rng.standard_normal((n, 3, 3)))
    Q = Q * np.sign(np.einsum("nii->ni", R))[:, None, :]
    Q[np.linalg.det(Q) < 0] *= -1.0
    return Q


def states(n: int = 20_000, seed: int = 0, material=TABLE1_STEEL):
    """(F, h) of the elastic and of the plastic case: F (n, 3, 3), h (n, n_history)."""
    rng = np.random.default_rng(seed)
    prm = material.params()[None]
    mid = np.zeros(n, np.int64)
    # elastic: |G| = 1 with amplitude 4e-4 stays below the yield strain σ_y0/E ≈ 1.3e-3
    G = rng.standard_normal((n, 3, 3))
    G /= np.linalg.norm(G, axis=(1, 2))[:, None, None]
    F_el = np.einsum("nij,njk->nik", _rotations(rng, n), np.eye(3) + 4e-4 * G)
    h_el = material.initial_history(n)
    # plastic: four steps to 0.02 along I + t G, then the timed step to 0.0205
    G = rng.standard_normal((n, 3, 3))
    G /= np.linalg.norm(G, axis=(1, 2))[:, None, None]
    h = material.initial_history(n)
    for t in (0.005, 0.01, 0.015, 0.02):
        _, h, st = kernels.material_points(np.ascontiguousarray(np.eye(3) + t * G), h, prm, mid)
    F_pl = np.ascontiguousarray(np.eye(3) + 0.0205 * G)
    _, h1, _ = kernels.material_points(F_pl, h, prm, mid)
    _, h0, _ = kernels.material_points(np.ascontiguousarray(F_el), h_el, prm, mid)
    if not (np.all(h1[:, HIST_EPS_P] > h[:, HIST_EPS_P]) and np.all(h0[:, HIST_EPS_P] == 0.0)):
        raise RuntimeError("bench states: the elastic/plastic cases are not what they claim")
    return {"elastic": (np.ascontiguousarray(F_el), h_el), "plastic": (F_pl, h)}


@njit(**JIT)
def _serial(point, F, h, prm, P, h_new, A, want_tangent):
    """The timed loop: ``point`` (a module's ``j2_point``) at every row, one thread."""
    for n in range(F.shape[0]):
        point(F[n], h[n], prm, P[n], h_new[n], A, want_tangent)


def _seconds(kern, F, h, prm, tangent: bool) -> float:
    P = np.empty((F.shape[0], 3, 3))
    h_new = np.empty_like(h)
    A = np.empty((3, 3, 3, 3))
    t0 = time.thread_time()  # CPU time of this thread: robust to other jobs on a shared machine
    _serial(kern.j2_point, F, h, prm, P, h_new, A, tangent)
    return time.thread_time() - t0


def points_per_second(kernel_modules, F, h_of, prm_of, tangent: bool, repeat: int = 5) -> list:
    """Points/s of each module's ``j2_point`` on (F, h_of(k), prm_of(k)): best of ``repeat``
    timed runs after one warm-up, the modules timed alternately in each round so that they see the
    same load of a shared machine."""
    for k, kern in enumerate(kernel_modules):
        _seconds(kern, F, h_of(k), prm_of(k), tangent)
    best = [np.inf] * len(kernel_modules)
    for _ in range(repeat):
        for k, kern in enumerate(kernel_modules):
            best[k] = min(best[k], _seconds(kern, F, h_of(k), prm_of(k), tangent))
    return [F.shape[0] / b for b in best]


def load_baseline(rev: str):
    """The kernels module of git revision ``rev``, imported from a temporary copy.

    Since the library became a package (one module per law, relative imports), the revision's
    ``workbench/materials/*.py`` are written into a temporary package ``workbench_kernels_<rev>``
    (its ``__init__`` left empty: the dataclasses there are not needed) and its ``kernels`` is
    imported from it; a revision with the single-file ``kernels.py`` loads the same way."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    git = lambda *a: subprocess.run(["git", *a], cwd=root, check=True, capture_output=True,
                                    text=True).stdout
    name = f"workbench_kernels_{rev}"
    base = os.path.join(tempfile.gettempdir(), name)
    pkg = os.path.join(base, name)
    os.makedirs(pkg, exist_ok=True)
    files = [f for f in git("ls-tree", "--name-only", rev, "workbench/materials/").split()
             if f.endswith(".py") and not f.endswith(("__init__.py", "bench.py"))]
    for f in files + ["__init__.py"]:
        src = git("show", f"{rev}:{f}") if f in files else ""
        path = os.path.join(pkg, os.path.basename(f))
        if not os.path.exists(path) or open(path).read() != src:
            with open(path, "w") as fh:
                fh.write(src)
    if base not in sys.path:
        sys.path.insert(0, base)  # numba's on-disk cache finds the modules again by their names
    return importlib.import_module(f"{name}.kernels")


def run(baseline: str | None = None, n: int = 20_000, repeat: int = 15) -> dict:
    """{case: {"current": points/s, "baseline": points/s (with ``baseline``)}}, one thread."""
    st = states(n)
    prm = TABLE1_STEEL.params()
    mods = [kernels] + ([load_baseline(baseline)] if baseline else [])
    n_prm = getattr(mods[-1], "N_PARAMS", BASELINE_N_PARAMS)
    n_hist = getattr(mods[-1], "N_HISTORY_J2", BASELINE_N_HISTORY)
    prm_base = np.ascontiguousarray(prm[:n_prm])
    prm_of = lambda k: prm if k == 0 else prm_base
    out = {}
    for case in CASES:
        F, h = st[case.split("+")[0]]
        h_base = np.ascontiguousarray(h[:, :n_hist])
        h_of = lambda k: h if k == 0 else h_base
        speeds = points_per_second(mods, F, h_of, prm_of, case.endswith("tangent"), repeat)
        out[case] = dict(zip(("current", "baseline"), speeds))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", help="git revision to time in the same run")
    ap.add_argument("--n", type=int, default=20_000, help="points per batch")
    ap.add_argument("--repeat", type=int, default=15)
    a = ap.parse_args(argv)
    res = run(a.baseline, a.n, a.repeat)
    print(f"J2 material point, 1 thread, {a.n} points, best of {a.repeat} "
          f"({os.cpu_count()} cores on this machine)")
    for case, row in res.items():
        line = f"  {case:17s} current {row['current']:10.3e} points/s"
        if "baseline" in row:
            line += (f"   baseline {row['baseline']:10.3e} points/s   "
                     f"ratio {row['current'] / row['baseline']:5.2f}")
        print(line)
    return res


if __name__ == "__main__":
    main(sys.argv[1:])
