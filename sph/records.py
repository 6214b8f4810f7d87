"""What an explicit run records (:meth:`sph.driver.Run.explicit`): at about ``n_out`` times, the
model's observables, the energies (kinetic, stored — contact included —, dissipated by kind,
external work) and their balance, the linear momentum, and the method's diagnostics.

The force a constraint exerts, read by a :class:`~workbench.scenes.model.Reaction`, is the mean
over the interval since the previous record: the driver adds each chunk's impulse to
:attr:`Records.impulse` and its length to :attr:`Records.span`, and a record divides one by the
other (at t = 0: the state's own force).
"""
from __future__ import annotations

import numpy as np

from workbench.scenes import model as M

from .diagnostics import linear_momentum

DIAGNOSTIC_RECORDS = 50
"""The method's diagnostics (a sparse product or two each) are evaluated at about this many
records and carried forward between them: at every record they cost 5 % of the plate's loop."""


class Records:
    """The histories of one explicit run of ``run`` (a :class:`sph.driver.Run`) with ``n_steps``
    steps recorded about ``n_out`` times; ``contact`` the contact's (rc, k, planes) or None."""

    def __init__(self, run, n_steps: int, n_out: int, contact):
        self.run, self.body, self.contact = run, run.body, contact
        self.n_steps = n_steps
        self.names = [n for o in run.model.observables if not isinstance(o, M.Period)
                      for n in M.record_names(o, run.ps.dim)]
        self.observed = {n: [] for n in self.names}
        self.times, self.ke, self.se, self.balance, self.momentum, self.work = [], [], [], [], [], []
        self.diagnostics, self.dissipated = {}, {}
        self.w_ext = 0.0  # work of the dead loads and of the constraints (prescribed motion)
        self.impulse = np.zeros_like(run.ps.X)  # of the constraint forces since the last record
        self.span = 0.0  # the time since the last record, s
        self.every_diag = max(1, n_out // DIAGNOSTIC_RECORDS)
        self.need_state = any(isinstance(o, (M.MeanStress, M.FailedFraction, M.CrackTip))
                              for o in run.model.observables)

    def take(self, on_record=None) -> None:
        """One record of the body's present state."""
        body = self.body
        fc, ce = None, 0.0
        if self.contact is not None:
            from .contact import contact_forces

            fc, ce = contact_forces(body.x, self.run.ps.body, *self.contact)
        force = (-self.impulse / self.span if self.span > 0 else body.acc * body.m[:, None])
        state = body.field_state() if self.need_state else None
        for n, v in self.run.observe(body.x, force, state, fc).items():
            self.observed[n].append(v)
        self.impulse[:] = 0.0
        self.span = 0.0
        ke, se = body.energies()
        se += ce
        self.times.append(body.t)
        fresh = ((len(self.times) - 1) % self.every_diag == 0 or body.steps >= self.n_steps
                 or not self.diagnostics)
        now = body.diagnostics() if fresh else {k: d[-1] for k, d in self.diagnostics.items()}
        for n, v in now.items():
            self.diagnostics.setdefault(n, []).append(v)
        lost = body.dissipated()
        for n, v in lost.items():
            self.dissipated.setdefault(n, []).append(v)
        self.ke.append(ke)
        self.se.append(se)
        self.work.append(self.w_ext)
        self.balance.append(ke + se + sum(lost.values()) - self.w_ext)
        self.momentum.append(linear_momentum(body.m, body.v))
        if on_record is not None:
            on_record(body, self.run, body.t)

    def arrays(self) -> dict:
        """The histories as arrays, by their names in the run's output."""
        out = dict(time=np.asarray(self.times), kinetic_energy=np.asarray(self.ke),
                   strain_energy=np.asarray(self.se), energy_history=np.asarray(self.balance),
                   external_work=np.asarray(self.work), linear_momentum=np.asarray(self.momentum))
        for group in (self.observed, self.diagnostics, self.dissipated):
            for n, v in group.items():
                out[n] = np.asarray(v)
        return out
