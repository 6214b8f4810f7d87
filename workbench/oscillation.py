"""The period and amplitude of a sampled history (the :class:`~workbench.scenes.model.Period`
observable), one definition for every method (particle methods and the FEM).

A history u(t) oscillates about its own mean c, which need not be zero: a beam released under its
own weight swings between its straight shape and twice its static sag, u never changes sign. The
period is therefore measured from the crossings of the level c, not of zero:

1. c₀ = the time mean of u over the record; the crossings of c₀ (after the first sample: a history
   that starts at its level, e.g. from an initial velocity, does not count its start);
2. c = the time mean over the whole cycles between the first crossing and the last crossing in
   the same direction (a whole number of periods: the mean of a drifting record's partial cycle
   does not bias it; for a history symmetric about zero c is zero to the sampling error), and the
   crossings of c;
3. the period is twice the least-squares slope of crossing time against crossing index (half a
   period per crossing), the crossing times interpolated linearly between samples.

A history that does not oscillate gives a NaN period and says why (``status``): fewer than
:data:`MIN_CROSSINGS` crossings (under ~1.5 cycles: a drift, a single swing), or an oscillation
about c no larger than round-off (:data:`ROUND_OFF` of the larger of ``scale`` — the size of the
coordinates the displacement is the difference of — and max |u|): its crossings are those of the
round-off noise (a plate started at 1e-300 of the wave speed shows "periods" of a few steps).
"""
from __future__ import annotations

import math

import numpy as np

MIN_CROSSINGS = 3
"""Crossings of the mean a history needs for a period: three (one whole cycle between the first
and the third, ~1.5 cycles of record) — the mean over a whole cycle needs them."""

ROUND_OFF = 1e-11
"""An oscillation whose amplitude about its mean is below this fraction of the signal's scale is
round-off: a displacement x − X carries eps |X| ≈ 2e-16 |X| per step, ≲ 2e-13 |X| after 1e6 steps
as a random walk; 1e-11 stays fifty-fold above that and far below any oscillation a run resolves."""


def peak(t: np.ndarray, u: np.ndarray) -> float:
    """max |u| (m) of a sampled history, each sampled maximum refined by the parabola through it
    and its two neighbours (for an oscillation sampled n times per period the plain maximum is
    low by ~(π/n)²/2, the refined one by O((π/n)⁴))."""
    a = np.abs(np.asarray(u, float))
    if len(a) == 0 or not np.isfinite(a).any():
        return math.nan
    k = int(np.nanargmax(a))
    if 0 < k < len(a) - 1 and np.all(np.isfinite(a[k - 1:k + 2])):
        y0, y1, y2 = a[k - 1], a[k], a[k + 1]
        h0, h1 = t[k] - t[k - 1], t[k + 1] - t[k]
        if h0 > 0 and h1 > 0:
            # parabola through the three samples: its vertex value
            c = ((y2 - y1) / h1 - (y1 - y0) / h0) / (h0 + h1)
            b = (y1 - y0) / h0 + c * h0
            if c < 0:
                return float(y1 - b * b / (4 * c))
    return float(a[k])


def crossings(t: np.ndarray, u: np.ndarray, level: float) -> np.ndarray:
    """Times at which u crosses ``level`` after the first sample, interpolated linearly."""
    t1, y1 = t[1:], u[1:] - level
    i = np.flatnonzero(np.sign(y1[:-1]) * np.sign(y1[1:]) < 0)
    return t1[i] - y1[i] * (t1[i + 1] - t1[i]) / (y1[i + 1] - y1[i])


def _mean_between(t: np.ndarray, u: np.ndarray, a: float, b: float) -> float:
    """The time mean of the piecewise-linear u over [a, b]."""
    inside = (t > a) & (t < b)
    tt = np.concatenate(([a], t[inside], [b]))
    uu = np.concatenate(([np.interp(a, t, u)], u[inside], [np.interp(b, t, u)]))
    return float(np.trapezoid(uu, tt) / (b - a))


def measure_period(t, u, scale: float = 0.0) -> dict:
    """Period (s) of the history u(t) about its mean (module docstring) and its amplitude.

    Returns ``period`` (NaN where u does not oscillate), ``amplitude`` max |u| (:func:`peak`, m:
    the largest displacement; for a history about zero the oscillation's amplitude), ``mean`` the
    level c (m), ``oscillation`` max |u − c| (m), ``crossings`` (their number) and ``status``:
    'ok', or 'no oscillation: …' saying why the period is NaN. ``scale``: the size of the
    coordinates u is a difference of (m; 0 when u is not one), for the round-off test."""
    t = np.asarray(t, float)
    u = np.asarray(u, float)
    out = dict(period=math.nan, amplitude=peak(t, u), mean=math.nan, oscillation=math.nan,
               crossings=0, status="ok")
    if len(u) < 3 or not np.all(np.isfinite(u)) or not np.all(np.diff(t) > 0):
        out["status"] = "no oscillation: the history is too short or not finite"
        return out
    c = _mean_between(t, u, t[0], t[-1])
    tc = crossings(t, u, c)
    if len(tc) >= MIN_CROSSINGS:
        c = _mean_between(t, u, tc[0], tc[2 * ((len(tc) - 1) // 2)])  # whole cycles
        tc = crossings(t, u, c)
    osc = float(np.max(np.abs(u - c)))
    out.update(mean=c, oscillation=osc, crossings=int(len(tc)))
    noise = ROUND_OFF * max(float(scale), float(np.max(np.abs(u))))
    if not osc > noise:
        out["status"] = (f"no oscillation: its amplitude about the mean, {osc:.3g} m, is at "
                         f"round-off (<= {noise:.3g} m)")
    elif len(tc) < MIN_CROSSINGS:
        out["status"] = (f"no oscillation: {len(tc)} crossing(s) of its mean {c:.4g} m, fewer "
                         f"than {MIN_CROSSINGS} (about 1.5 cycles)")
    else:
        out["period"] = float(2 * np.polyfit(np.arange(len(tc)), tc, 1)[0])
    return out


def period_amplitude(t: np.ndarray, u: np.ndarray, scale: float = 0.0) -> tuple[float, float]:
    """(period, amplitude) of :func:`measure_period`."""
    m = measure_period(t, u, scale)
    return m["period"], m["amplitude"]


def with_period_notes(status: str, out: dict, names) -> str:
    """A run's ``status`` with the reason of each period (observable ``names``) that has no value
    appended, 'ok (period: no oscillation: …)', where the run itself is ok: a number that cannot
    be measured is not reported as one, and the status a study stores says why (the solver's
    own ``status`` stays that of the run; ``out[name + '_status']`` holds each period's own,
    :func:`measure_period`)."""
    if status != "ok":
        return status
    notes = [f"{n}: {out[f'{n}_status']}" for n in names if out.get(f"{n}_status", "ok") != "ok"]
    return f"ok ({'; '.join(notes)})" if notes else status
