"""Convergence reports: observed orders by least squares over a resolution ladder, and the ladder
extended by one more level when the order is not yet settled, within a time budget.

The order is *settled* when the local orders of the last two pairs of levels agree within
``tol`` (0.3 by default): then one more level would not change the least-squares slope by much.
The cost of the next level is predicted from the fitted power law of wall time against resolution.
"""
from __future__ import annotations

import numpy as np

from .common import observed_order


def local_orders(res, err) -> np.ndarray:
    """Order between consecutive levels: log(e_i/e_{i+1}) / log(r_{i+1}/r_i)."""
    res = np.asarray(res, float)
    err = np.abs(np.asarray(err, float))
    return np.log(err[:-1] / err[1:]) / np.log(res[1:] / res[:-1])


def settled(res, err, tol: float = 0.3) -> bool:
    """Whether the last two local orders agree within ``tol`` (needs at least three levels)."""
    ok = np.isfinite(err) & (np.abs(err) > 0)
    res, err = np.asarray(res)[ok], np.asarray(err)[ok]
    if len(res) < 3:
        return False
    p = local_orders(res, err)
    return bool(abs(p[-1] - p[-2]) <= tol)


def predicted_time(res, wall, new_res) -> float:
    """Wall time of ``new_res`` from a power-law fit of the ladder's wall times."""
    res = np.asarray(res, float)
    wall = np.asarray(wall, float)
    ok = np.isfinite(wall) & (wall > 0)
    if ok.sum() < 2:
        return float("inf")
    k, c = np.polyfit(np.log(res[ok]), np.log(wall[ok]), 1)
    return float(np.exp(c) * new_res ** k)


def extend(res, err, wall, budget: float, tol: float = 0.3) -> int | None:
    """The next resolution (twice the finest) if the order is not settled and its predicted wall
    time fits in ``budget`` seconds; None otherwise."""
    if settled(res, err, tol):
        return None
    nxt = 2 * int(max(res))
    return nxt if predicted_time(res, wall, nxt) <= budget else None


def report(res, err) -> dict:
    """The least-squares order over the ladder, the local orders and whether it is settled."""
    return dict(order=observed_order(1.0 / np.asarray(res, float), err),
                local=[float(p) for p in local_orders(res, err)] if len(res) > 1 else [],
                settled=settled(res, err))
