"""The ``workbench`` command line (``../shared/design/contract.md``).

Every input is checked before any work starts (:func:`_validated`): scene parameters (finite, in
range, lists not empty), solvers, resolutions (and the memory each run would need against this
machine's), the output folder (a probe file is written), the scheduler (it must answer within
seconds), the budget. Bad input prints one line naming the parameter and its allowed range and
exits with status 2, without a traceback. A dataset that cannot be written where asked is saved in
a fallback folder the one-line message names (exit status 1); an interrupted run (Ctrl-C) says
that its finished runs are in the run cache and that the same command resumes (exit status 130).
"""
from __future__ import annotations

import argparse
import logging
import math
import sys
from pathlib import Path

import numpy as np

from workbench import results
from workbench.scenes import ParameterError, with_overrides


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


FEM_CHECKS = {
    "steps_per_period": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 2,
                         "an integer >= 2 (Newmark steps per lowest modal period)"),
    "maxit": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 1, "an integer >= 1"),
    "field_frames": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 1, "an integer >= 1"),
    "rtol": (lambda v: isinstance(v, (int, float)) and 0 < v < 1, "(0, 1)"),
    "max_increment": (lambda v: isinstance(v, (int, float)) and v > 0, "(0, inf]"),
    "min_increment": (lambda v: isinstance(v, (int, float)) and v > 0, "(0, inf)"),
    "initial_tangent": (lambda v: isinstance(v, bool), "true or false"),
    "fbar": (lambda v: v is None or isinstance(v, bool), "true, false or none"),
    "deletion": (lambda v: isinstance(v, bool), "true or false"),
    "element": (lambda v: v in ("q9", "q4", "hex27", "hex8"), "q9, q4, hex27, hex8"),
}
"""The FEM's options settable from the command line (``--option fem.KEY=VALUE``), with their
allowed values (``fem_reference.model.solve_model``)."""


def _option_value(text: str):
    """A command-line value: a Python literal (number, True/False/None, string), else the text."""
    import ast

    low = {"true": True, "false": False, "none": None}.get(text.strip().lower(), ...)
    if low is not ...:
        return low
    try:
        return ast.literal_eval(text.strip())
    except (ValueError, SyntaxError):
        return text.strip()


def parse_options(items, allowed, solvers, scene, resolution: int = 5) -> dict:
    """``--option METHOD.KEY=VALUE`` items as {method: {key: value}}, each checked before any
    run: the method one of ``allowed`` (and of the ``solvers`` asked for, when given), the key
    one of its options, the value accepted — by the FEM's table :data:`FEM_CHECKS`, and for a
    particle method by building its body on the scene at ``resolution`` (the method's own checks).
    UsageError (one line) otherwise."""
    out: dict = {}
    for item in items or []:
        head, eq, text = item.partition("=")
        method, dot, key = head.strip().partition(".")
        if not (eq and dot and method and key):
            raise UsageError(f"--option: {item!r} is not METHOD.KEY=VALUE (e.g. sph.stress=hyperelastic)")
        if method not in allowed:
            raise UsageError(f"--option: method {method!r} cannot run this scene; allowed: "
                             f"{', '.join(allowed)}")
        if solvers and method not in solvers:
            raise UsageError(f"--option: method {method!r} is not among the --solver runs "
                             f"({', '.join(solvers)})")
        value = _option_value(text)
        if method == "fem":
            if key not in FEM_CHECKS:
                raise UsageError(f"--option: {key!r} is not an option of fem; allowed: "
                                 f"{', '.join(FEM_CHECKS)}")
            ok, rng = FEM_CHECKS[key]
            if not ok(value):
                raise UsageError(f"--option: fem.{key} = {text!r} is out of range; allowed: {rng}")
        else:
            from sph.driver import method_entry

            mod, _ = method_entry(method)
            if key not in mod.OPTIONS:
                raise UsageError(f"--option: {key!r} is not an option of {method}; allowed: "
                                 f"{', '.join(mod.OPTIONS)}")
        out.setdefault(method, {})[key] = value
    for method, opts in out.items():
        if method != "fem":
            _try_build(method, opts, scene, resolution)
    return out


def _try_build(method: str, options: dict, scene, resolution: int) -> None:
    """Build ``method``'s body with ``options`` on ``scene`` at ``resolution``: the method's own
    checks of its options, as one line (a scene that cannot be discretised is left to the run,
    which reports it)."""
    from sph.driver import method_entry, model_at
    from sph.particles import discretise

    mod, defaults = method_entry(method)
    try:
        ps = discretise(model_at(scene, resolution)[0], resolution)
    except Exception:  # the run says what is wrong with the scene
        return
    try:
        mod.build(ps, **{**defaults, **options})
    except (ValueError, TypeError) as err:
        shown = ", ".join(f"{method}.{k}={v!r}" for k, v in options.items())
        raise UsageError(f"--option {shown}: {_one_line(err)}") from None


def _print_parameters(scene_cls) -> None:
    for p in scene_cls.parameters():
        default = p["default"]
        if isinstance(default, tuple):
            default = ",".join(f"{d:g}" for d in default)
        print(f"    {p['name']:<14} = {default!s:<22} [{p['units']}] {p['range']:<16} {p['doc']}")


def cmd_list(args) -> int:
    import studies

    if args.file:
        cls = load_scene(args.file)
        scene = user_code(args.file, cls)
        user_code(args.file, scene.model)
        print(f"{cls.__name__} ({args.file}): solvers {', '.join(_scene_solvers(scene))}")
        print(f"  {(cls.__doc__ or '').strip().splitlines()[0] if cls.__doc__ else ''}")
        _print_parameters(cls)
        length = cls().model().length
        print(f"  resolution r: r intervals across the model's length {length:g} m (spacing "
              f"{length:g}/r m; r + 1 particles across it on the node lattice, r elements)")
        return 0
    for name in studies.STUDIES:
        study = studies.get(name)
        print(f"{name}: solvers {', '.join(study.SOLVERS)}")
        print(f"  {(study.__doc__ or '').strip().splitlines()[0]}")
        _print_parameters(study.SCENE)
    print("Resolution r: r intervals across the scene's reference length (H for the headline "
          "scenes): spacing H/r, r + 1 particles across H on the node lattice, r elements.")
    print("A scene of your own: workbench run my_scene.py[:SceneClass] (README: 'Your own scene').")
    return 0


def is_scene_file(name: str) -> bool:
    return name.split(":")[0].endswith(".py")


def load_scene(spec: str):
    """The Scene class of a user's file: ``path.py`` (the one Scene subclass it defines) or
    ``path.py:ClassName``. UsageError (one line) when it cannot be found."""
    import importlib.util
    import inspect

    from workbench.scenes import Scene

    path, _, cls_name = spec.partition(":")
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"scene file: {path!r} does not exist")
    mod_name = f"workbench_user_scene_{abs(hash(str(p.resolve())))}"
    spec_ = importlib.util.spec_from_file_location(mod_name, p)
    mod = importlib.util.module_from_spec(spec_)
    sys.modules[mod_name] = mod
    try:
        spec_.loader.exec_module(mod)
    except Exception as err:
        raise UsageError(f"scene file: {path}{_line_in(p, err)} could not be loaded "
                         f"({type(err).__name__}: {err})") from None
    found = {n: c for n, c in vars(mod).items() if inspect.isclass(c) and issubclass(c, Scene)
             and c is not Scene and c.__module__ == mod_name}
    if cls_name:
        if cls_name not in found:
            raise UsageError(f"scene file: {path} defines no Scene subclass {cls_name!r} "
                             f"(found: {', '.join(found) or 'none'})")
        return found[cls_name]
    if len(found) != 1:
        raise UsageError(f"scene file: {path} defines {len(found)} Scene subclasses "
                         f"({', '.join(found) or 'none'}); name one as {path}:ClassName")
    return next(iter(found.values()))


def _line_in(path: Path, err: BaseException) -> str:
    """' line N': the last line of the file ``path`` the error passed through (the line of the
    user's code that failed, or that called the library that refused it); '' if none."""
    target = path.resolve()
    line = getattr(err, "lineno", None) if isinstance(err, SyntaxError) else None
    tb = err.__traceback__
    while tb is not None:
        try:
            if Path(tb.tb_frame.f_code.co_filename).resolve() == target:
                line = tb.tb_lineno
        except OSError:  # pragma: no cover - a frame without a file
            pass
        tb = tb.tb_next
    return f" line {line}" if line else ""


def user_code(spec: str, fn, *args):
    """``fn(*args)`` for code of the user's scene file ``spec`` (its class, ``model()``): any
    exception becomes one line naming the file, the line and the cause (UsageError, exit 2); a
    model that does not hold together (ParameterError, SceneError) keeps its own words after
    the file and the line."""
    path = Path(spec.partition(":")[0])
    try:
        return fn(*args)
    except Exception as err:
        name = getattr(fn, "__name__", "the scene")
        cause = str(err) if isinstance(err, ParameterError) else f"failed ({type(err).__name__}: {err})"
        raise UsageError(f"scene file: {path}{_line_in(path, err)}: {name}() {cause}") from None


def _scene_solvers(scene) -> tuple:
    from studies import scene as generic

    return generic.solvers_for(scene.model())


def _check_common(args) -> None:
    """The options every command that runs studies shares: the output folder (created and proved
    writable by a probe file), the scheduler (reachable), the budget (a finite number >= 0)."""
    from studies.sweep import check_scheduler

    budget = getattr(args, "budget", 0.0)
    if budget is not None and not (math.isfinite(budget) and budget >= 0):
        raise UsageError(f"--budget: {budget:g} is out of range; allowed: [0, inf) s (finite)")
    try:
        results.check_writable(args.out)
    except results.OutputError as err:
        raise UsageError(f"--out: {err}") from None
    try:
        check_scheduler(args.scheduler)
    except ParameterError as err:
        raise UsageError(f"--{err}") from None


def _validated(args):
    """The study, scene and resolutions of ``workbench run``, every input checked before any work
    starts (module doc); UsageError or ParameterError (one line) otherwise."""
    import studies
    from studies.common import validate

    if is_scene_file(args.study):
        from studies import scene as study

        cls = load_scene(args.study)
        scene = with_overrides(user_code(args.study, cls), _parse_sets(args.set))
        user_code(args.study, scene.model)  # an error in the user's model(): one line, exit 2
        allowed = _scene_solvers(scene)
    else:
        try:
            study = studies.get(args.study)
        except ValueError as err:
            raise UsageError(f"{err}; or a scene file (my_scene.py)") from None
        scene = with_overrides(study.SCENE(), _parse_sets(args.set))
        allowed = study.SOLVERS
    cracks = scene.model().cracks if is_scene_file(args.study) else ()
    for s in args.solver or []:
        if s == "fem" and cracks:
            raise UsageError(f"--solver: 'fem' does not cut elements along pre-crack "
                             f"'{cracks[0].name}'; allowed: {', '.join(allowed)}")
        if s not in allowed:
            raise UsageError(f"--solver: {s!r} is not supported by {args.study}; allowed: "
                             f"{', '.join(allowed)}")
    resolutions = list(args.resolution) if args.resolution else None
    if args.option and not is_scene_file(args.study):
        raise UsageError(f"--option: {args.study} sets its methods' options itself; --option is "
                         "for a scene file (my_scene.py)")
    validate(study, scene, args.solver, resolutions, args.quick)  # incl. the memory of every run
    options = parse_options(args.option, allowed, args.solver, scene,
                            min(resolutions) if resolutions else 5)
    _check_common(args)
    return study, scene, resolutions, options


def cmd_run(args) -> int:
    from studies.sweep import recording

    from .verify import run_study

    study, scene, resolutions, options = _validated(args)
    name = scene.name if is_scene_file(args.study) else args.study
    with recording() as runs:
        section = run_study(name, args.out, args.quick, solvers=args.solver,
                            resolutions=resolutions, scene=scene, scheduler=args.scheduler,
                            budget=args.budget, fields=args.fields, study=study,
                            options=options)
    ds = section["dataset"]
    print(f"{name}: {section.get('written', Path(args.out) / (name + '.nc'))}")
    if args.fields:
        series = [n.strip() for n in str(ds.attrs.get("field_series", "")).split(",") if n.strip()]
        print(f"  fields: {', '.join(str(Path(args.out) / 'fields' / n) for n in series) or 'none written'}")
    info = {(r["solver"], r["resolution"]): r for r in runs}
    for r in section["rows"]:
        print(f"  {r['solver']:<8} resolution {r['resolution']:<4} error {r['error']:.3e}  "
              f"wall {r['wall_time']:.3f} s{_cost_note(info.get((r['solver'], r['resolution'])))}")
    for g in section["gates"]:
        print("  " + g.line())
    if is_scene_file(args.study):
        _print_observables(ds, info)
    if hasattr(study, "run_outcomes"):  # the study says which runs that did not end ok are results
        return _judged_by_study(study.run_outcomes(ds), section["gates"])
    bad = [str(s) for s in np.atleast_1d(ds["status"].values).ravel()
           if not (str(s).startswith("ok") or str(s) == "not run")]
    if bad:
        print(f"  failed runs: {sorted(set(bad))}")
    return 1 if bad else 0


def _judged_by_study(outcomes: list[dict], gates) -> int:
    """Print the runs that did not end ok, each marked expected (and why) or not, and return the
    exit status of a study that judges its own runs (the stability map: an instability is a
    result): 1 when a gate failed or a run failed (an error), else 0."""
    if outcomes:
        print(f"  runs that did not end ok ({len(outcomes)}):")
    for o in outcomes:
        mark = ("FAILED" if o["failed"] else
                f"expected: {o['expected']}" if o["expected"] else "not expected; judged by the gates")
        print(f"    {o['run']:<32} {o['status']}  [{mark}]")
    failed = [o["run"] for o in outcomes if o["failed"]]
    if failed:
        print(f"  failed runs: {failed}")
    return 1 if failed or not all(g.passed for g in gates) else 0


def _cost_note(rec) -> str:
    """'  (cached)' for a run served from the run cache, else its set-up and JIT times (the wall
    time beside it is the solver's own)."""
    if rec is None:
        return ""
    if rec["cached"]:
        return "  (cached)"
    parts = [f"{k} {rec[v]:.2f} s" for k, v in (("set-up", "setup_time"), ("JIT", "jit_time"))
             if math.isfinite(rec.get(v, math.nan))]
    return f"  ({', '.join(parts)})" if parts else ""


def _print_observables(ds, info=None) -> None:
    """The last value of every observable of a scene run, per solver and resolution."""
    axis = next((d for d in ("parameter", "time", "mode") if d in ds.dims), None)
    names = [v for v in ds.data_vars if axis is not None and axis in ds[v].dims]
    names += [v for v in ds.data_vars if ds[v].dims == ("solver", "resolution")
              and v not in ("status", "wall_time", "n_particles") and ds[v].dtype.kind in "fiu"]
    for s in ds.solver.values:
        for r in ds.resolution.values:
            st = str(ds.status.sel(solver=s, resolution=r).values)
            if st == "not run":
                continue
            vals = []
            for v in names:
                y = np.atleast_1d(ds[v].sel(solver=s, resolution=r).values)
                ok = y[np.isfinite(y)]
                vals.append(f"{v} {ok[-1]:.5g} {ds[v].attrs.get('units', '')}" if ok.size else f"{v} -")
            wall = float(ds.wall_time.sel(solver=s, resolution=r))
            note = _cost_note((info or {}).get((str(s), int(r))))
            print(f"  {s:<5} resolution {int(r):<4} {st:<6} wall {wall:7.2f} s{note}  " + "; ".join(vals))


def cmd_verify(args) -> int:
    from .verify import verify

    _check_common(args)
    return verify(args.out, args.quick, args.scheduler, args.budget)


def cmd_bench(args) -> int:
    from studies import bench

    try:
        results.check_writable(args.out)
    except results.OutputError as err:
        raise UsageError(f"--out: {err}") from None
    try:
        return bench.main(args)
    except bench.UsageError as err:
        raise UsageError(str(err)) from None


def cmd_docs(args) -> int:
    from . import apidoc

    try:
        results.check_writable(args.out)
    except results.OutputError as err:
        raise UsageError(f"--out: {err}") from None
    print(f"API reference of the scene vocabulary: {apidoc.build(args.out)}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="workbench", description=__doc__.splitlines()[0])
    p.add_argument("-v", "--verbose", action="store_true", help="log every run")
    # -v after the subcommand as well (SUPPRESS: absent there, the main parser's value stands)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS,
                        help="log every run")
    sub = p.add_subparsers(dest="command", required=True)
    lp = sub.add_parser("list", help="studies, their solvers and parameters", parents=[common])
    lp.add_argument("file", nargs="?", help="a scene file (my_scene.py[:SceneClass]): its parameters")
    lp.set_defaults(fn=cmd_list)
    r = sub.add_parser("run", help="run one study, or a scene file (my_scene.py[:SceneClass])",
                       parents=[common])
    r.add_argument("study")
    r.add_argument("--solver", action="append", help="a method (repeatable)")
    r.add_argument("--resolution", action="append", type=int,
                   help="r intervals across the scene's reference length: spacing length/r, r + 1 "
                        "particles, r elements across it (repeatable)")
    r.add_argument("--set", action="append", metavar="NAME=VALUE", help="override a scene parameter")
    r.add_argument("--option", action="append", metavar="METHOD.KEY=VALUE",
                   help="a method's option for a scene file, e.g. sph.stress=hyperelastic or "
                        "fem.steps_per_period=400 (repeatable)")
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
    v = sub.add_parser("verify", help="run the headline studies, apply the gates, write the report",
                       parents=[common])
    v.add_argument("--quick", action="store_true")
    v.add_argument("--out", default="results")
    v.add_argument("--scheduler", help="'local' (default; 'serial' with --quick) or a dask "
                                       "scheduler address")
    v.add_argument("--budget", type=float, default=0.0,
                   help="seconds for extending unsettled convergence ladders (default 0: off)")
    v.set_defaults(fn=cmd_verify)
    b = sub.add_parser("bench", help="particle-steps per second of a scene's time loop",
                       parents=[common])
    b.add_argument("--scene", help="plate (default), microcantilever3d or rc_beam")
    b.add_argument("--solver", action="append")
    b.add_argument("--particles", action="append", type=int)
    b.add_argument("--threads", action="append", type=int)
    b.add_argument("--out", default="results")
    b.set_defaults(fn=cmd_bench)
    d = sub.add_parser("docs", help="the API reference of the scene vocabulary (HTML, from the docstrings)",
                       parents=[common])
    d.add_argument("--out", default="docs/api")
    d.set_defaults(fn=cmd_docs)
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
        print(f"workbench: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except (results.SavedElsewhere, results.WriteFailed, results.PartlyWritten) as err:
        print(f"workbench: error: {_one_line(err)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        from studies.sweep import cache_dir

        where = cache_dir()
        kept = (f"finished runs are kept in the run cache ({where}): run the same command again "
                "to resume" if where is not None else "the run cache is off (WORKBENCH_NO_CACHE=1): "
                "nothing was kept")
        print(f"workbench: interrupted; {kept}", file=sys.stderr)
        return 130


def _one_line(err) -> str:
    return " ".join(str(err).split())


if __name__ == "__main__":
    sys.exit(main())
