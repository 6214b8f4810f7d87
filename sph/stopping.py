"""The stop rules of an explicit run: what ends the driver's time loop before ``t_end``.

Each rule is checked after every record (:class:`sph.records.Records`), in the order
:func:`explicit_rules` gives; the first that fires ends the run with its criterion and status, and
each adds what it measured to the run's output (:meth:`Rule.report`):

* :class:`EnergyRule` — the drive's ``energy_growth``: the energy balance's gain growing
  exponentially (:class:`sph.monitor.EnergyGrowth`; status ``unstable``), and the drift and
  dissipation of the balance over the run;
* :class:`SeparationRule` — the drive's ``separate``: ``after`` seconds past the first record at
  which no chain of intact particles joins two sets (status ``ok``; ``t_separated``,
  ``at_separation``);
* :class:`DisorderRule` — the drive's ``disorder``: particle disorder η₉₅ above the limit
  (:class:`sph.monitor.Disorder`; status ``unstable``);
* :class:`ThresholdRule` — each :class:`~workbench.scenes.model.Threshold` of the drive's ``stop``:
  ``after`` seconds past the first record at which an observable crosses a value (status ``ok``;
  ``t_threshold``).

A non-finite state is not a rule: the time loop itself reports it (:meth:`sph.driver.Run.explicit`).
"""
from __future__ import annotations

import math

import numpy as np

from .monitor import Disorder, EnergyGrowth, energy_floor


class Rule:
    """A stop rule: :meth:`check` after each record returns None (go on) or (criterion, status)."""

    def check(self, body, records) -> tuple[str, str] | None:
        return None

    def report(self, out: dict, status: str) -> None:
        """Add what the rule measured to the run's output ``out`` (``status`` the run's)."""


class EnergyRule(Rule):
    """Exponential growth of the energy balance's gain beyond ``tol`` of the largest energy seen
    (:class:`sph.monitor.EnergyGrowth`); with ``tol`` None the run is not monitored, and the
    balance's drift over the run is not reported (NaN)."""

    def __init__(self, body, records, tol: float | None):
        self.tol = tol
        self.scale = abs(records.ke[0] + records.se[0])  # the largest total energy seen
        self.growth = None
        if tol is not None:
            self.growth = EnergyGrowth(energy_floor(float(np.sum(body.m)), body.wave_speed()),
                                       tol, self.scale)
            self.growth.update(0, records.balance[0], records.ke[0] + records.se[0])

    def check(self, body, records):
        if self.growth is None:
            return None
        total = records.ke[-1] + records.se[-1]
        self.scale = max(self.scale, abs(total))
        grew, change, rate = self.growth.update(body.steps, records.balance[-1], total)
        if grew:
            return "energy", (f"unstable: energy balance grew by {change:+.3g} of the energy "
                              f"scale, exponentially ({rate:.3g} per step), at t={body.t:.4g} s")
        return None

    def finish(self, out: dict, balance, status: str) -> None:
        """``energy_drift`` (the balance's change over the run over the energy scale; NaN
        unmonitored), ``dissipated`` (its loss, ≥ 0) and a ``note`` where that exceeds ``tol``."""
        e = np.asarray(balance)
        drift = float((e[-1] - e[0]) / self.scale) if self.scale > 0 else math.nan
        if self.tol is None:
            drift = math.nan
        out["energy_drift"] = drift
        out["dissipated"] = max(0.0, -drift) if math.isfinite(drift) else math.nan
        tol = self.tol if self.tol is not None else math.inf
        out["note"] = (f"dissipated {100 * out['dissipated']:.3g} % of the initial energy"
                       if status == "ok" and out["dissipated"] > tol else "")


class SeparationRule(Rule):
    """The drive's ``separate`` = (a, b): ``after`` seconds past the first record at which the
    run's :meth:`~sph.driver.Run.separated` finds the two sets apart; the state then
    (:meth:`~sph.driver.Run.cut_state`) in ``at_separation``."""

    def __init__(self, run, sets: tuple[str, str], after: float):
        self.run, self.sets, self.after = run, sets, after
        self.t_cut = None
        self.at_cut = None

    def check(self, body, records):
        if self.t_cut is None and self.run.separated(*self.sets):
            self.t_cut = body.t
            self.at_cut = self.run.cut_state(records.dissipated)
        if self.t_cut is not None and body.t >= self.t_cut + self.after * (1 - 1e-9):
            return "separated", "ok"
        return None

    def report(self, out, status):
        out["t_separated"] = math.nan if self.t_cut is None else float(self.t_cut)
        out["at_separation"] = self.at_cut


class DisorderRule(Rule):
    """Particle disorder η₉₅ (:class:`sph.monitor.Disorder`, on the drive's ``disorder_set``)
    above the drive's ``disorder``; measured at about 50 of the records (carried forward between
    them) and at the last; ``disorder_history`` the values at every record."""

    def __init__(self, run, drive, body):
        ps = run.ps
        mask = None
        if drive.disorder_set is not None:
            mask = np.zeros(ps.n, bool)
            mask[ps.sets[drive.disorder_set]] = True
        self.limit = drive.disorder
        self.n_steps = None
        self.every = max(1, drive.n_out // 50)
        self.measure = Disorder(ps.X, ps.dx, body=ps.body if len(ps.body_names) > 1 else None,
                                mask=mask, cracks=ps.cracks)
        self.history = [self.measure(body.x)[0]]
        self.X = ps.X

    def check(self, body, records):
        fresh = (len(records.times) - 1) % self.every == 0 or body.steps >= records.n_steps
        d95 = self.measure(body.x)[0] if fresh else self.history[-1]
        self.history.append(d95)
        if d95 > self.limit:
            return "disorder", (f"unstable: particle disorder eta95 = {d95:.3g} > {self.limit} "
                                f"at t={body.t:.4g} s")
        return None

    def finish(self, out, body, status):
        ok_x = np.isfinite(body.x).all()
        d95, dmax = self.measure(body.x) if ok_x else (math.nan, math.nan)
        out.update(stable=status == "ok", disorder=d95, disorder_max=dmax,
                   min_spacing=self.measure.min_spacing(body.x) if ok_x else math.nan,
                   disorder_history=np.asarray(self.history), x=body.x.copy(), X=self.X.copy())


class ThresholdRule(Rule):
    """A :class:`~workbench.scenes.model.Threshold` of the drive's ``stop`` on the last recorded
    value of its observable."""

    def __init__(self, threshold):
        self.threshold = threshold
        self.t_crossed = None

    def check(self, body, records):
        if self.t_crossed is None and self.threshold.holds(records.observed[self.threshold.of][-1]):
            self.t_crossed = body.t
        if self.t_crossed is not None and body.t >= self.t_crossed + self.threshold.after * (1 - 1e-9):
            return "threshold", "ok"
        return None

    def report(self, out, status):
        """``t_threshold``: the time of the first crossing of the rules of the drive (NaN if
        none crossed), ``threshold`` which rule it was."""
        if not math.isfinite(out.setdefault("t_threshold", math.nan)) and self.t_crossed is not None:
            out["t_threshold"] = float(self.t_crossed)
            out["threshold"] = self.threshold.describe()


def explicit_rules(run, drive, body, records) -> dict:
    """The rules of the explicit ``drive`` for ``run``, by kind: ``energy`` (always present: it
    also reports the balance's drift), ``separate``, ``disorder``, and ``stop`` (a list), in the
    order they are checked."""
    rules = {"energy": EnergyRule(body, records, drive.energy_growth)}
    if drive.separate is not None:
        rules["separate"] = SeparationRule(run, drive.separate, drive.after)
    if drive.disorder is not None and math.isfinite(drive.disorder):
        rules["disorder"] = DisorderRule(run, drive, body)
    rules["stop"] = [ThresholdRule(s) for s in getattr(drive, "stop", ())]
    return rules


def ordered(rules: dict) -> list:
    """The rules of :func:`explicit_rules` as one list, in the order they are checked."""
    return [r for k, r in rules.items() if k != "stop"] + list(rules["stop"])
