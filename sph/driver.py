"""The one particle driver: any scene model, any particle method, one run.

``solve(method, scene, resolution, **options)``:

1. **discretise** — ``scene.model()`` at the spacing ``length / resolution``
   (:func:`sph.particles.discretise`: regions → particles with a material row, a body and a held
   flag each; named sets → particle indices and probes);
2. **build** the method's body (:data:`sph.METHODS`; ``options`` go to its ``build``);
3. **loads and constraints** — held particles and clamps fix every DOF, rollers (symmetry planes)
   one, prescribed motion moves DOFs; tractions, pressures, point and body forces become dead
   particle forces f_ext (a particle's share of a surface load is its boundary area on that surface);
4. **drive** — :class:`~workbench.scenes.model.Static`: Newton on the gradient form with load
   stepping (:mod:`sph.static`), or, for a method without one (classic SPH), dynamic relaxation
   through its own explicit step (:mod:`sph.relaxation`); :class:`~workbench.scenes.model.Modal`: the eigenproblem
   K φ = ω² M φ of the same tangent about X with lumped masses; :class:`~workbench.scenes.model.Explicit`:
   the method's fused time loop in chunks (contact: the generic velocity Verlet with the method's
   force plus :mod:`sph.contact`, weighted on the symmetry planes: :meth:`Run.mirror_planes`),
   loads that vary in time updated at chunk midpoints (chunks of at most
   :data:`MAX_CHUNK_VARYING` steps then; the records stay about ``n_out``);
5. **stop rules** — explicit: the rules of :mod:`sph.stopping` after every record (the one
   stability criterion of :mod:`sph.monitor`; with the drive's ``separate``, ``after`` seconds
   past the first record at which no chain of intact particles joins two sets —
   :meth:`Run.separated`, a crack has cut the body: status ``ok``, criterion ``separated``, the
   time in ``t_separated``, the state then in ``at_separation``: :meth:`Run.cut_state`; the
   drive's :class:`~workbench.scenes.model.Threshold` rules: criterion ``threshold``, the time
   in ``t_threshold``); static: the path ends at the first value where a Threshold holds;
6. **measure** — the model's observables after every load value (static) or chunk (explicit), the
   energies, field snapshots (``fields=<folder>``) between chunks; the scene's
   :meth:`~workbench.scenes.params.Scene.summarise` adds its study's quantities.

Reactions and energies of an explicit run. The force a constraint exerts on a DOF it moves at the
velocity v_fix is r = m dv_fix/dt − f (f internal plus dead force); its impulse over a chunk is
m Δv_fix − ∫ f dt, with ∫ f dt the trapezoid sum the method's time loop adds up
(:attr:`sph.method.ParticleBody.impulse`), and a :class:`~workbench.scenes.model.Reaction` is the
time mean of Σ r over the interval since the previous record. The external work is that of the dead
loads, Σ f_ext · Δx, plus that of the constraints, Σ ½ m Δ(v_fix²) at each change of v_fix and
−v_fix · ∫ f dt over each chunk — velocity Verlet's own discrete work on those DOFs, so that
``external_work`` = ``kinetic_energy`` + ``strain_energy`` + the energies the body reports as
dissipated (:meth:`sph.method.ParticleBody.dissipated`: plastic work, energy released by failure)
holds to the time integration's error.

Returns a dict: ``status`` (or one per load value), ``parameter`` / ``time``, every observable by
name (an array over the load values or records), energies (explicit, J — J/m in 2-D — at each
record: ``kinetic_energy``, ``strain_energy``, ``external_work``, and ``plastic_work``,
``released_energy`` where the body reports them; ``energy_history`` their balance), ``wall_time``
(the solver's own cost: the time loop or the Newton iterations, without set-up and JIT
compilation; static: cumulative at each load value), ``setup_time`` (discretisation, method
build, loads), ``jit_time`` (:func:`jit_estimate`), ``total_time`` (the whole call), ``loop_time``
(explicit: the time loop alone, JIT included), ``n_particles``, ``dt``, ``steps``, the final state
(explicit: ``X``, ``x`` (N, d) m, ``region`` (N,) with ``region_names``, ``sets`` name →
indices, ``history`` the final material history (rows as the body's field state),
``volume`` (N,) the volumes its work columns are integrated with, m³, where the body says,
``failed_particles`` (N,) bool where the model observes failure, ``component`` (N,) the connected
parts where the method reports them, :meth:`sph.method.ParticleBody.components`), and the scene's
quantities.
"""
from __future__ import annotations

import contextlib
import dataclasses
import importlib
import math
import time

import numpy as np

from workbench import progress
from workbench.fields import DEFAULT_FRAMES, Snapshots, series_name
from workbench.oscillation import measure_period
from workbench.scenes import model as M
from workbench.scenes.params import SceneError

from . import METHODS
from .particles import TOL, Particles, discretise
from .records import Records
from .stopping import explicit_rules, ordered

def jit_estimate(first_time: float, first_work: float, rest_time: float, rest_work: float) -> float:
    """The JIT compilation (and numba cache loading) in a loop's first chunk, s: its time less
    what its work (steps or Newton iterations) costs at the rate of the later chunks; 0 without
    later chunks to measure the rate on."""
    if rest_work <= 0 or rest_time <= 0:
        return 0.0
    return max(0.0, first_time - first_work * rest_time / rest_work)


MAX_CHUNK_VARYING = 20
"""Longest chunk of steps (over which loads are held at their mid-chunk value) when a load or a
prescribed motion varies in time."""


@contextlib.contextmanager
def threads_for(n_particles: int):
    """One numba thread for a body under :data:`sph.total_lagrangian.SERIAL_BELOW` particles
    (waking the thread pool for every small parallel loop costs more than the loop), the
    configured threads otherwise."""
    import numba

    from .total_lagrangian import SERIAL_BELOW

    nt = numba.get_num_threads()
    if n_particles < SERIAL_BELOW:
        numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(nt)


def method_module(name: str):
    """The module of the particle method ``name`` (:data:`sph.METHODS`)."""
    return method_entry(name)[0]


def method_entry(name: str):
    """(module, default options) of the particle method ``name`` (:data:`sph.METHODS`)."""
    if name not in METHODS:
        raise ValueError(f"solver: {name!r} is not a particle method; allowed: {', '.join(METHODS)}")
    mod, defaults = METHODS[name]
    return importlib.import_module(mod), dict(defaults)


def model_at(scene, resolution: int):
    """The scene's model at the spacing of ``resolution`` (geometry may depend on it, e.g. a
    clamp of a whole number of particle layers) and that spacing."""
    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise SceneError(f"resolution: {resolution!r} is not allowed; an integer >= 1")
    length = scene.model().length
    dx = length / int(resolution)
    return scene.model(dx), dx


def solve(method: str, scene, resolution: int, lattice: str | None = None, fields=None,
          field_frames: int = DEFAULT_FRAMES, drive=None, static: str = "newton",
          on_record=None, **options) -> dict:
    """Run the particle method ``method`` on ``scene`` at ``resolution`` (module docstring).
    ``lattice`` overrides the model's ('node' or 'cell'); ``drive`` replaces the model's (e.g.
    ``Modal()`` for the linearised periods of a dynamic scene); ``static``: 'newton' (default) or
    'dr' (dynamic relaxation, for the cost comparison); ``fields`` (a folder, or None) writes the
    ParaView series ``<scene>_<method>_H<resolution>.pvd``; ``on_record(body, run, t)`` is called
    at every record of an explicit drive, t = 0 included, and at every equilibrium of a static
    one (t the load parameter), to look at the state in between (e.g.
    :mod:`studies.stability_theory`) — a static path stops where it returns true (the later
    values' status :data:`workbench.results.STOPPED`); the other ``options`` go to the method's
    ``build``."""
    t0 = time.perf_counter()
    mod, defaults = method_entry(method)
    options = {**defaults, **options}
    model, _ = model_at(scene, resolution)
    if drive is not None:
        model = dataclasses.replace(model, drive=drive)
    ps = discretise(model, int(resolution), lattice)
    body = mod.build(ps, **options)
    run = Run(model, ps, body)
    snap_name = series_name(scene.name, method, resolution)
    with threads_for(ps.n):
        if isinstance(model.drive, M.Static):
            out = run.static(fields, snap_name, t0, static, on_record)
        elif isinstance(model.drive, M.Modal):
            out = run.modal()
        else:
            out = run.explicit(fields, snap_name, field_frames, t0, on_record,
                               getattr(mod, "DISORDER", None))
    out["total_time"] = time.perf_counter() - t0
    out.setdefault("n_particles", int(ps.n))
    out["n_free"] = int(np.count_nonzero(~run.fixed.all(axis=1)))
    out["plane"] = model.plane
    out["lattice"] = ps.lattice
    if isinstance(model.drive, type(scene.model().drive)):
        out.update(scene.summarise(out))
    return out


class Run:
    """The loads, constraints and observables of a model on a particle body."""

    def __init__(self, model: M.Model, ps: Particles, body):
        self.model = model
        self.ps = ps
        self.body = body
        self.prescribed = [c for c in model.constraints if isinstance(c, M.Prescribed)]
        self.crack_paths = {}  # CrackTip name -> its path (K, d) at the latest record
        self.fixed = ps.fixed
        self.varying = bool(self.prescribed) or any(
            not isinstance(getattr(ld, "scale", 1.0), (int, float)) and
            not (isinstance(ld.scale, M.Table) and len(ld.scale.times) == 1)
            for ld in model.loads if hasattr(ld, "scale"))

    # -- loads ---------------------------------------------------------------------------------
    def dead_forces(self, at: float) -> np.ndarray:
        """f_ext (N, d), N, of the dead loads at the load parameter / time ``at``."""
        ps = self.ps
        normals = self.body.normals if self.body.normals is not None else ps.normals
        f = np.zeros((ps.n, ps.dim))
        for ld in self.model.loads:
            if isinstance(ld, M.InitialVelocity):
                continue
            s = float(M.as_function(ld.scale)(at))
            if isinstance(ld, M.Traction):
                idx = ps.sets[ld.set]
                f[idx] += s * np.outer(ps.surface_area(ld.set, normals), np.asarray(ld.traction, float))
            elif isinstance(ld, M.Pressure):
                idx = ps.sets[ld.set]
                f[idx] -= s * ld.pressure * normals[idx]
            elif isinstance(ld, M.PointLoad):
                idx, w = ps.probes[ld.set] if ld.set in ps.probes else (
                    ps.sets[ld.set], np.full(len(ps.sets[ld.set]), 1.0 / len(ps.sets[ld.set])))
                np.add.at(f, idx, s * np.outer(w, np.asarray(ld.force, float)))
            elif isinstance(ld, M.BodyForce):
                sel = ps.in_regions(ld.regions)
                f[sel] += s * np.outer(self.body.m[sel], np.asarray(ld.acceleration, float))
        return f

    def initial_velocity(self) -> np.ndarray:
        ps = self.ps
        v = np.zeros((ps.n, ps.dim))
        for ld in self.model.loads:
            if isinstance(ld, M.InitialVelocity):
                sel = ps.in_regions(ld.regions) & ~ps.held
                vel = ld.velocity
                v[sel] = vel(ps.X[sel]) if callable(vel) else np.asarray(vel, float)
        v[self.fixed] = 0.0
        return v

    def prescribed_targets(self, lam: float) -> np.ndarray:
        """Positions of the fixed DOFs at the load parameter λ (static drives), (N, d)."""
        x = self.ps.X.copy()
        for c in self.prescribed:
            x[self.ps.sets[c.set], c.axis] += float(M.as_function(c.displacement)(lam))
        return x

    def prescribed_velocity(self, t: float, dt: float) -> np.ndarray:
        """v_fix (N, d) at time t (explicit drives): the prescribed velocity, or the displacement's
        difference quotient over [t − dt/2, t + dt/2]."""
        v = np.zeros((self.ps.n, self.ps.dim))
        for c in self.prescribed:
            if c.velocity is not None:
                val = float(M.as_function(c.velocity)(t))
            else:
                u = M.as_function(c.displacement)
                val = float((u(t + 0.5 * dt) - u(t - 0.5 * dt)) / dt)
            v[self.ps.sets[c.set], c.axis] = val
        return v

    # -- observables ---------------------------------------------------------------------------
    def observe(self, x, force=None, state=None, contact=None) -> dict:
        """The model's observables at positions x; ``force`` the total force f_int + f_ext (N, d)
        for reactions; ``state`` a field state for stresses and damage; ``contact`` the contact
        forces (N, d) for :class:`~workbench.scenes.model.ContactForce` (NaN without)."""
        ps = self.ps
        out = {}
        for o in self.model.observables:
            if isinstance(o, M.ContactForce):
                sel = ps.body == ps.body_names.index(o.body)
                out[o.name] = math.nan if contact is None else float(contact[sel, o.axis].sum())
                continue
            if isinstance(o, M.Momentum):
                sel = ps.body == ps.body_names.index(o.body)
                out[o.name] = float(self.body.m[sel] @ self.body.v[sel, o.axis])
                continue
            if isinstance(o, M.Displacement):
                if o.set in ps.probes:
                    idx, w = ps.probes[o.set]
                    out[o.name] = float(w @ (x[idx, o.axis] - ps.X[idx, o.axis]))
                else:
                    idx = ps.sets[o.set]
                    V = ps.V[idx]
                    out[o.name] = float(V @ (x[idx, o.axis] - ps.X[idx, o.axis]) / V.sum())
            elif isinstance(o, M.Position):
                out[o.name] = float(np.mean(x[ps.sets[o.set], o.axis]))
            elif isinstance(o, M.Reaction):
                out[o.name] = math.nan if force is None else -float(force[ps.sets[o.set], o.axis].sum())
            elif isinstance(o, M.MeanStress):
                out[o.name] = self._mean_stress(o, state)
            elif isinstance(o, M.FailedFraction):
                out[o.name] = self._failed_fraction(o, state)
            elif isinstance(o, M.CrackTip):
                out.update(self._crack_tip(o, state))
        return out

    def _crack_tip(self, o, state) -> dict:
        """The :class:`~workbench.scenes.model.CrackTip` ``o`` now: the path of the failed
        particles of its regions (:meth:`_failed_mask`) from its origin, in the reference
        configuration (:func:`workbench.crack_geometry.crack_path`); the speed is filled in by
        :meth:`tip_speeds` once the history is known."""
        from workbench.crack_geometry import crack_path

        ps = self.ps
        origin, ref = self.model.tip_origin(o)
        failed = self._failed_mask(state) & ps.in_regions(o.regions)
        p = crack_path(ps.X[failed], origin, o.spacing * ps.dx, ref)
        self.crack_paths[o.name] = p.path
        names = [n for n, _ in o.outputs(ps.dim)]
        vals = [*p.tip, p.length, p.angle, math.nan]
        return dict(zip(names, (float(v) for v in vals)))

    def tip_speeds(self, out: dict, t) -> None:
        """``<name>_speed`` of each :class:`~workbench.scenes.model.CrackTip` in ``out``: the
        difference quotient of its length over the records' times (or load values) ``t``, 0 at
        the first (m/s, or m per unit load parameter); and ``<name>_path`` (K, d), m, the path
        (origin, centroids, tip) at the last record."""
        for o in self.model.observables:
            if not isinstance(o, M.CrackTip):
                continue
            out[f"{o.name}_path"] = self.crack_paths.get(o.name)
            L = np.asarray(out[f"{o.name}_length"], float)
            tt = np.asarray(t, float)[:len(L)]
            v = np.zeros(len(L))
            if len(L) > 1:
                with np.errstate(invalid="ignore", divide="ignore"):
                    v[1:] = np.diff(L) / np.diff(tt)
            out[f"{o.name}_speed"] = v

    def _mean_stress(self, o, state) -> float:
        from workbench.materials import evaluate

        if state is None:
            return math.nan
        sel = self.ps.in_regions(o.regions)
        if "sigma" in state:
            sig = np.asarray(state["sigma"])
            J = np.asarray(state.get("J", np.ones(self.ps.n)))
        else:
            F = np.ascontiguousarray(state["F"])
            sig = evaluate(self.ps.table, F, state["history"], stress="sigma",
                           mat_id=self.ps.mat_id)["stress"]
            J = np.linalg.det(F)
        w = self.ps.V[sel] * J[sel]
        return float(np.sum(w * sig[sel, o.i, o.j]) / np.sum(w))

    def _failed_mask(self, state) -> np.ndarray:
        """(N,) bool: the failed particles, whatever their law
        (:func:`workbench.materials.failure.failed`: damage ≥ 1 — J2's D, the mortar fully
        released along some axis, the brittle law's crack fully opened; none without a history).
        The one place the particle solvers and observables ask."""
        from workbench.materials.failure import failed

        if state is None or state.get("history") is None:
            return np.zeros(self.ps.n, bool)
        return failed(self.ps.table, self.ps.mat_id, state["history"])

    def _failed_fraction(self, o, state) -> float:
        sel = self.ps.in_regions(o.regions)
        failed = self._failed_mask(state)
        return float(np.count_nonzero(failed[sel]) / max(1, np.count_nonzero(sel)))

    # -- static --------------------------------------------------------------------------------
    def static(self, fields, snap_name, t0, method: str = "newton", on_record=None) -> dict:
        from .static import Constraints, solve_path

        tlb = self.body.gradient_form()  # None: dynamic relaxation by the method's own step
        drive = self.model.drive
        path = np.asarray(drive.path, dtype=float)
        names = [n for o in self.model.observables for n in M.record_names(o, self.ps.dim)]
        out = dict(parameter=path, parameter_name=drive.parameter,
                   wall_time=np.full(len(path), np.nan), iterations=np.zeros(len(path), int),
                   **{n: np.full(len(path), np.nan) for n in names})
        if drive.stop:
            out["t_threshold"] = math.nan  # the load parameter at which a stop rule held
        snap = Snapshots.open(fields, snap_name, self.ps.X, self.ps.table,
                              lambda: dict(self.body.field_state(), t=state["lam"]),
                              len(path), 1, max(1, len(path)))
        state = dict(lam=0.0)
        bar = progress.bar(len(path), snap_name, unit="load", delay=2.0, leave=False)
        t_start = time.perf_counter()
        setup_time = t_start - t0
        its_at = []

        def constraints_at(lam):
            return Constraints(self.fixed, self.dead_forces(lam)), self.prescribed_targets(lam)

        def on_equilibrium(k, lam, x, its, f=None):
            self.body.x[:] = x
            if f is None:
                f = tlb.evaluate(x) + self.dead_forces(lam)
            st = self.body.field_state()
            for n, v in self.observe(x, f, st).items():
                out[n][k] = v
            out["iterations"][k] = its
            out["wall_time"][k] = time.perf_counter() - t_start
            its_at.append((k, its))
            stop = on_record is not None and on_record(self.body, self, lam)
            held = [r for r in drive.stop if r.holds(out[r.of][k])]
            if held and not math.isfinite(out.get("t_threshold", 0.0)):
                out["t_threshold"], out["threshold"] = float(lam), held[0].describe()
            stop = stop or bool(held)
            bar.update(1)
            if snap:
                state["lam"] = lam
                snap(k + 1)
            return stop

        try:
            if tlb is None:
                from .relaxation import relax_path

                out["status"] = relax_path(self.body, path, constraints_at, on_equilibrium)
            else:
                out["status"] = solve_path(tlb, self.ps.X.copy(), path, constraints_at,
                                           on_equilibrium, method=method)
        finally:
            bar.close()
        # the solver's own time: the first load step's JIT compilation estimated from the rate
        # (s per Newton iteration or relaxation step) of the later steps, reported apart with the
        # set-up
        wt = out["wall_time"]
        jit = 0.0
        if its_at and its_at[0][0] == 0:  # iterations per load value
            its = np.array([i for _, i in its_at], float)
            jit = jit_estimate(wt[0], its[0], float(np.nanmax(wt) - wt[0]), float(its[1:].sum()))
        out["wall_time"] = wt - jit
        out["jit_time"] = jit
        out["setup_time"] = setup_time
        self.tip_speeds(out, path)
        return out

    # -- modal ---------------------------------------------------------------------------------
    def modal(self) -> dict:
        import scipy.sparse as sp
        import scipy.sparse.linalg as spla

        t0 = time.perf_counter()
        tlb = self.body.gradient_form()
        if tlb is None:
            raise ValueError(f"drive: {self.body.name} has no modal solve (a gradient-form method: "
                             "csph or hpm)")
        _, A = tlb.evaluate(self.ps.X.copy(), tangent=True)
        K = tlb.tangent(A)
        free = ~self.fixed.ravel()
        Kf = K[free][:, free].tocsc()
        Mm = sp.diags(np.repeat(self.body.m, self.ps.dim)[free]).tocsc()
        w2 = spla.eigsh(Kf, k=self.model.drive.n_modes, M=Mm, sigma=0, which="LM",
                        return_eigenvectors=False)
        periods = np.sort(2 * np.pi / np.sqrt(np.abs(w2)))[::-1]
        return dict(periods=periods, period=float(periods[0]), status="ok",
                    wall_time=time.perf_counter() - t0)

    # -- explicit ------------------------------------------------------------------------------
    def start_explicit(self, v0_scale: float = 1.0):
        """Start the body for the explicit drive: the time step (``dt_factor`` times the CFL
        estimate, or times the critical step 2/ω_max with ``dt_reference='spectrum'``), the held
        components (N, d) uint8, the dead loads and prescribed velocities at t = 0, the contact
        force callback (None without contact), and the body started from the initial velocity
        (× ``v0_scale``). Returns (dt, fixed, f_ext, v_fix, extra, contact), ``contact`` the
        contact's (rc, k, planes) or None. The driver's explicit run and the benchmarks
        (studies.bench) start a body through this one path."""
        drive = self.model.drive
        body, ps = self.body, self.ps
        dt = body.time_step(drive.dt_factor)
        if getattr(drive, "dt_reference", "cfl") == "spectrum":  # × the critical step 2/ω_max
            from .spectrum import critical_time_step

            dt *= critical_time_step(body, self.fixed) / body.time_step(1.0)
        fixed = np.ascontiguousarray(self.fixed, dtype=np.uint8)
        f_ext = self.dead_forces(0.0)
        v_fix = self.prescribed_velocity(0.0, dt) if self.prescribed else np.zeros_like(ps.X)
        contact = self._contact_setup()
        extra = None
        if contact is not None:
            from .contact import contact_forces

            def extra(x):
                return contact_forces(x, ps.body, *contact)[0]
        body.start(self.initial_velocity() * v0_scale, f_ext, extra)
        return dt, fixed, f_ext, v_fix, extra, contact

    def explicit(self, fields, snap_name, field_frames, t0, on_record=None,
                 default_disorder: float | None = None) -> dict:
        """The explicit drive (module docstring): the method's time loop in chunks between the
        records (:class:`sph.records.Records`), the stop rules checked after each record
        (:mod:`sph.stopping`). ``default_disorder``: the method's own η₉₅ limit (its module's
        ``DISORDER``: classic SPH's known failure, particle disorder, is monitored by default),
        used where the drive gives none and every material is elastic (no history): a body that
        can yield or fail (J2, mortar) disorders by fracturing, which is its result, not a
        failure of the method."""
        drive = self.model.drive
        if (drive.disorder is None and default_disorder is not None
                and self.ps.table.n_history == 0):
            drive = dataclasses.replace(drive, disorder=default_disorder)
        body, ps = self.body, self.ps
        dt, fixed, f_ext, v_fix, extra, contact = self.start_explicit()
        n_steps = int(math.ceil(drive.t_end / dt))
        every = max(1, n_steps // drive.n_out)  # steps between records
        chunk = min(every, MAX_CHUNK_VARYING) if self.varying else every
        snap = Snapshots.open(fields, snap_name, ps.X, ps.table, body.field_state, n_steps, chunk,
                              field_frames)
        from .method import ParticleBody

        tracked = (extra is not None or type(body).advance is ParticleBody.advance
                   or body.impulse_in_loop)
        fx = self.fixed
        m_dof = np.broadcast_to(body.m[:, None], fx.shape)
        records = Records(self, n_steps, drive.n_out, contact)
        records.take(on_record)
        rules = explicit_rules(self, drive, body, records)
        if snap:
            snap(0)
        status, criterion = "ok", "none"
        t_loop = 0.0
        first = None  # (time, steps) of the first chunk: JIT compilation happens there
        bar = progress.bar(n_steps, snap_name, unit="step", delay=2.0, leave=False)
        t_setup = time.perf_counter() - t0
        next_record = every
        while body.steps < n_steps:
            k = min(chunk, n_steps - body.steps)
            if self.varying:
                tm = body.t + 0.5 * k * dt
                f_new = self.dead_forces(tm)
                if self.prescribed:
                    v_fix = self.prescribed_velocity(tm, dt)
            else:
                f_new = f_ext
            x_before = body.x.copy()
            # a change of the prescribed velocity: the constraint's impulse m Δv and work Δ(½ m v²)
            dv = np.where(fx, v_fix - body.v, 0.0)
            records.impulse += m_dof * dv
            records.w_ext += 0.5 * float(np.sum(m_dof * dv * (v_fix + body.v)))
            f_before = body.acc * body.m[:, None]
            body.impulse[:] = 0.0
            tl0 = time.perf_counter()
            done = body.advance(k, dt, f_new, fixed, v_fix, drive.damping, extra)
            t_loop += time.perf_counter() - tl0
            first = first or (t_loop, done)
            bar.update(done)
            records.w_ext += float(np.sum(f_new * (body.x - x_before)))
            # the constraints: r = −f on a DOF moving at v_fix, work −v_fix · ∫ f dt
            imp = (body.impulse if tracked else
                   0.5 * done * dt * (f_before + body.acc * body.m[:, None]))
            imp = np.where(fx, imp, 0.0)
            records.w_ext -= float(np.sum(v_fix * imp))
            records.impulse -= imp
            records.span += done * dt
            f_ext = f_new
            if done < k or not np.isfinite(body.x).all():
                criterion = "non-finite"
                why = "material point failed (J <= 0 or return mapping)" if body.failed() else "non-finite state"
                status = f"unstable: {why} at t={body.t:.6g} s"
                break
            if snap:
                snap(body.steps)
            if body.steps < min(next_record, n_steps):
                continue  # loads varying in time: chunks shorter than the interval of records
            next_record = (body.steps // every + 1) * every
            records.take(on_record)
            fired = None
            for rule in ordered(rules):
                fired = rule.check(body, records)
                if fired is not None:
                    break
            if fired is not None:
                criterion, status = fired
                break
        bar.close()
        if snap:
            snap(body.steps, final=True)
        jit = jit_estimate(*first, t_loop - first[0], body.steps - first[1]) if first else 0.0
        out = dict(records.arrays(), status=status, criterion=criterion, dt=dt,
                   steps=int(body.steps),
                   wall_time=t_loop - jit, jit_time=jit, loop_time=t_loop, setup_time=t_setup,
                   n_particles=int(ps.n),
                   # the loop's own rate: JIT compilation left out, as from wall_time
                   particle_steps_per_second=(ps.n * body.steps / (t_loop - jit)
                                              if t_loop - jit > 0 else math.nan))
        self.tip_speeds(out, out["time"])
        for rule in ordered(rules):
            rule.report(out, status)
        out.setdefault("t_separated", math.nan)
        out.setdefault("at_separation", None)
        # the final state: reference and current positions, regions, and the failed particles
        state = body.field_state()
        out.update(X=ps.X.copy(), x=body.x.copy(), v=body.v.copy(), region=ps.region.copy(),
                   region_names=list(ps.region_names),
                   sets={k: np.asarray(v).copy() for k, v in ps.sets.items()},
                   **self.material_state(state))
        if state.get("V") is not None:  # the volumes of the history's work columns
            out["volume"] = np.array(state["V"])
        parts = body.components()
        if parts is not None:
            out["component"] = np.asarray(parts)
        rules["energy"].finish(out, records.balance, status)
        self._periods(out, status)
        if "disorder" in rules:
            rules["disorder"].finish(out, body, status)
        return out

    def _periods(self, out: dict, status: str) -> None:
        """Each :class:`~workbench.scenes.model.Period` of the model, from the recorded history
        of its displacement (:func:`workbench.oscillation.measure_period`; NaN with the reason in
        ``<name>_status`` where the run is not ok or does not oscillate)."""
        size = float(np.abs(self.ps.X).max())  # u = x − X carries the round-off of x: the scale
        for o in self.model.observables:
            if not isinstance(o, M.Period):
                continue
            m = dict(period=math.nan, amplitude=math.nan, status=f"no oscillation: the run is {status}")
            if status == "ok":
                m = measure_period(out["time"], out[o.of], size)
            out[o.name] = m["period"]
            out[f"{o.name}_amplitude"] = m["amplitude"]
            out[f"{o.name}_status"] = m["status"]

    def cut_state(self, dissipated: dict) -> dict:
        """What a study measures of a crack when it has just cut the body (``at_separation``):
        the material ``history``, ``failed_particles`` where the model observes failure, and the
        dissipated energies at the record (``dissipated``: name -> values so far, the last one
        taken) — what fails later (the fragments moving on, for ``after``) left out."""
        return {**{n: float(v[-1]) for n, v in dissipated.items()}, **self.material_state()}

    def material_state(self, state: dict | None = None) -> dict:
        """A copy of the body's material ``history`` ((N, 0) without one) and, where the model
        observes failure, its ``failed_particles``, from ``state`` (the body's field state; now
        when None)."""
        state = self.body.field_state() if state is None else state
        h = state.get("history")
        out = dict(history=np.zeros((self.ps.n, 0)) if h is None else np.array(h))
        if any(isinstance(o, (M.FailedFraction, M.CrackTip)) for o in self.model.observables):
            out["failed_particles"] = self._failed_mask(state)
        return out

    def separated(self, a: str, b: str) -> bool:
        """Whether no chain of intact particles joins the sets ``a`` and ``b`` (the method's
        ``components``; False where the method does not say)."""
        parts = self.body.components()
        if parts is None:
            return False
        sets = self.ps.sets
        return not set(np.unique(parts[sets[a]])) & set(np.unique(parts[sets[b]]))

    # -- contact: the generic velocity Verlet ---------------------------------------------------
    def _contact_setup(self):
        if not self.model.contact:
            return None
        c = self.model.contact[0]
        for o in self.model.contact[1:]:
            if (o.stiffness, o.distance) != (c.stiffness, c.distance):
                raise SceneError(f"contact {o.bodies}: stiffness and distance must equal those of "
                                 f"contact {c.bodies} (one penalty acts between all bodies)")
        return (c.distance if c.distance is not None else self.ps.dx, c.stiffness,
                self.mirror_planes())

    def mirror_planes(self):
        """The contact's plane bit masks (:func:`sph.contact.mirror_planes`) on the symmetry planes
        (:func:`sph.mirror.symmetry_planes`: a :class:`~workbench.scenes.model.Roller` on a
        :class:`~workbench.scenes.shapes.Plane` set with the roller's axis as its normal, the body
        on one side; a frictionless wall is one too): a contact pair of particles both of its set
        and on the plane carries half its force. None without such planes."""
        from .contact import mirror_planes
        from .mirror import symmetry_planes

        planes = [(a, at, self.ps.sets[name])
                  for a, at, name in symmetry_planes(self.model, self.ps, TOL * self.ps.dx)]
        if not planes:
            return None
        return mirror_planes(self.ps.X, planes, TOL * self.ps.dx)  # the sets' own tolerance


def scene_time_steps(method: str, scene, resolution: int, lattice: str | None = None,
                     **options) -> dict:
    """The time steps of ``method`` on ``scene`` at ``resolution`` (the body and constraints that
    :func:`solve` builds; :mod:`sph.spectrum`): ``dt_cfl`` (Δx/c_p, the CFL estimate at factor 1),
    ``dt_crit`` (eq. 1), ``omega_max`` (rad/s) and ``n_free`` (free DOFs), s."""
    from .particles import discretise
    from .spectrum import max_frequency

    mod, defaults = method_entry(method)
    model, _ = model_at(scene, resolution)
    ps = discretise(model, int(resolution), lattice)
    body = mod.build(ps, **{**defaults, **options})
    fixed = Run(model, ps, body).fixed
    w = max_frequency(body, fixed)
    return dict(dt_cfl=body.time_step(1.0), dt_crit=2.0 / w if w > 0 else math.inf, omega_max=w,
                n_free=int(np.count_nonzero(~np.asarray(fixed, bool))))
