"""The ``workbench`` command line (``../shared/design/contract.md``).

Bad input (an unknown study, solver or parameter, a value out of range) prints one line naming the
parameter and its allowed range and exits with status 2, without a traceback.
"""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

import numpy as np

from .scenes import ParameterError, with_overrides


class UsageError(Exception):
    """A bad command-line value: printed as one line, exit status 2."""


def _parse_sets(items) -> dict[str, str]:
    out = {}
    for item in items or []:
        if "=" not in item:
            raise UsageError(f"--set: {item!r} is not NAME=VALUE")
        k, v = item.split("=", 1)
        out[k.strip()] = v.strip()
    return out


def cmd_list(args) -> int:
    import studies

    for name in studies.STUDIES:
        study = studies.get(name)
        print(f"{name}: solvers {', '.join(study.SOLVERS)}")
        print(f"  {(study.__doc__ or '').strip().splitlines()[0]}")
        for p in study.SCENE.parameters():
            default = p["default"]
            if isinstance(default, tuple):
                default = ",".join(f"{d:g}" for d in default)
            print(f"    {p['name']:<14} = {default!s:<22} [{p['units']}] {p['range']:<16} {p['doc']}")
    return 0


def _validated(args):
    import studies
    from studies.common import check_resolutions

    try:
        study = studies.get(args.study)
    except ValueError as err:
        raise UsageError(str(err)) from None
    for s in args.solver or []:
        if s not in study.SOLVERS:
            raise UsageError(f"--solver: {s!r} is not supported by {args.study}; allowed: "
                             f"{', '.join(study.SOLVERS)}")
    try:
        resolutions = check_resolutions(args.resolution) if args.resolution else None
    except ValueError as err:
        raise UsageError(str(err)) from None
    scene = with_overrides(study.SCENE(), _parse_sets(args.set))
    return study, scene, resolutions


def cmd_run(args) -> int:
    from .verify import run_study

    study, scene, resolutions = _validated(args)
    section = run_study(args.study, args.out, args.quick, solvers=args.solver,
                        resolutions=resolutions, scene=scene, scheduler=args.scheduler,
                        budget=args.budget, fields=args.fields)
    ds = section["dataset"]
    print(f"{args.study}: {Path(args.out) / (args.study + '.nc')}")
    if args.fields:
        series = [n.strip() for n in str(ds.attrs.get("field_series", "")).split(",") if n.strip()]
        print(f"  fields: {', '.join(str(Path(args.out) / 'fields' / n) for n in series) or 'none written'}")
    for r in section["rows"]:
        print(f"  {r['solver']:<8} resolution {r['resolution']:<4} error {r['error']:.3e}  "
              f"wall {r['wall_time']:.3f} s")
    for g in section["gates"]:
        print("  " + g.line())
    bad = [str(s) for s in np.atleast_1d(ds["status"].values).ravel()
           if not (str(s).startswith("ok") or str(s) == "not run")]
    if bad:
        print(f"  failed runs: {sorted(set(bad))}")
    return 1 if bad else 0


def cmd_verify(args) -> int:
    from .verify import verify

    return verify(args.out, args.quick, args.scheduler, args.budget)


def cmd_bench(args) -> int:
    try:
        from sph import bench
    except ImportError:
        raise UsageError("bench: the particle benchmark is not available in this build") from None
    return bench.main(args)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="workbench", description=__doc__.splitlines()[0])
    p.add_argument("-v", "--verbose", action="store_true", help="log every run")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="studies, their solvers and parameters").set_defaults(fn=cmd_list)
    r = sub.add_parser("run", help="run one study")
    r.add_argument("study")
    r.add_argument("--solver", action="append", help="a method (repeatable)")
    r.add_argument("--resolution", action="append", type=int, help="particles/elements across (repeatable)")
    r.add_argument("--set", action="append", metavar="NAME=VALUE", help="override a scene parameter")
    r.add_argument("--out", default="results")
    r.add_argument("--quick", action="store_true")
    r.add_argument("--scheduler", help="'serial' (default), 'local' (dask cluster of this machine's "
                                       "cores) or a dask scheduler address")
    r.add_argument("--budget", type=float, default=0.0,
                   help="seconds for extending an unsettled convergence ladder (default 0: off)")
    r.add_argument("--fields", action="store_true",
                   help="write the particle runs' fields (displacement, velocity, stress, ε_p, "
                        "damage) as ParaView series (.pvd + .vtp) under OUT/fields/")
    r.set_defaults(fn=cmd_run)
    v = sub.add_parser("verify", help="run the headline studies, apply the gates, write the report")
    v.add_argument("--quick", action="store_true")
    v.add_argument("--out", default="results")
    v.add_argument("--scheduler", help="'local' (default; 'serial' with --quick) or a dask "
                                       "scheduler address")
    v.add_argument("--budget", type=float, default=0.0,
                   help="seconds for extending unsettled convergence ladders (default 0: off)")
    v.set_defaults(fn=cmd_verify)
    b = sub.add_parser("bench", help="particle-steps per second of the plate time loop")
    b.add_argument("--solver", action="append")
    b.add_argument("--particles", action="append", type=int)
    b.add_argument("--threads", action="append", type=int)
    b.add_argument("--out", default="results")
    b.set_defaults(fn=cmd_bench)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if (args.verbose or args.command == "verify") else logging.WARNING,
                        format="%(asctime)s %(message)s", datefmt="%H:%M:%S")
    for noisy in ("skfem", "distributed", "tornado", "bokeh"):  # the cluster's own chatter
        logging.getLogger(noisy).setLevel(logging.WARNING)
    try:
        return int(args.fn(args) or 0)
    except (UsageError, ParameterError) as err:
        print(f"workbench: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
