"""The one notion of a failed (cracked) material point, for every law (issue 41 item 3).

A law that can fail keeps a damage in [0, 1] in one history column, and a point has failed once
it has reached 1:

* J2 (:mod:`workbench.materials.j2`): D = ε_p/ε_L (column ``HIST_DAMAGE``) — it carries no
  tension or shear from then on (``failure`` 'compression') or nothing ('literal');
* the mortar of 003 (:mod:`workbench.materials.mortar`): the largest eigenvalue of the damage
  tensor, clipped to 1 (``H_DAMAGE``) — some direction fully released, its stress across the crack
  gone (the same as the ``H_RELEASED`` flag: the damage never decreases);
* the brittle law (:mod:`workbench.materials.brittle`): the damage d (``H_DAMAGE``) — the crack
  fully opened, no tension or shear.

The elastic laws cannot fail. Every reader asks here: the failure observables
(``FailedFraction``, ``failed_particles``: ``sph.driver.Run._failed_mask`` and the FEM's
``fem_reference.observe.failed_elements``), the connectivity and separation check and csph's crack
rule (:mod:`sph.crack`), and the field output's ``damage``. :func:`set_failed` starts points
already failed (the scene's ``InitiallyFailed``), whatever law that can fail they are of.
"""
from __future__ import annotations

import numpy as np

from . import brittle as _brittle
from . import mortar as _mortar
from .layout import HIST_DAMAGE


def damage_column(material) -> int:
    """The history column holding the damage of a :class:`Material`'s law (failed once ≥ 1), or
    −1 for a law that cannot fail (the elastic laws). J2 has the column whatever its ε_L (without
    a damage limit, ε_L = ∞, D stays 0 under load, but a point set failed is failed)."""
    if material.law == "j2":
        return HIST_DAMAGE
    if material.law == "mortar":
        return _mortar.H_DAMAGE
    if material.law == "brittle":
        return _brittle.H_DAMAGE
    return -1


def damage_columns(table) -> np.ndarray:
    """(n_materials,) int64: :func:`damage_column` of each material of a table."""
    from . import MaterialTable

    return np.array([damage_column(m) for m in MaterialTable.of(table).materials], np.int64)


def can_fail(table) -> bool:
    """Whether some material of the table can fail under load: J2 with a finite ε_L, the mortar,
    the brittle law."""
    from . import MaterialTable

    return any(damage_column(m) >= 0 and not (m.law == "j2" and not np.isfinite(m.eps_L))
               for m in MaterialTable.of(table).materials)


def damage(table, mat_id, history) -> np.ndarray:
    """(N,) the damage of each point, failed at ≥ 1 (0 for a law that cannot fail, or without a
    history): J2's D = ε_p/ε_L, the mortar's largest damage eigenvalue (clipped to 1), the
    brittle law's d."""
    mat_id = np.asarray(mat_id, np.int64)
    out = np.zeros(mat_id.shape[0])
    if history is None or np.shape(history)[1] == 0:
        return out
    h = np.asarray(history)
    col = damage_columns(table)[mat_id]
    on = (col >= 0) & (col < h.shape[1])
    out[on] = h[np.flatnonzero(on), col[on]]
    return out


def failed(table, mat_id, history) -> np.ndarray:
    """(N,) bool: the points that have failed (module docstring): damage ≥ 1."""
    mat_id = np.asarray(mat_id, np.int64)
    if history is None or np.shape(history)[1] == 0:
        return np.zeros(mat_id.shape[0], bool)
    h = np.asarray(history)
    col = damage_columns(table)[mat_id]
    on = (col >= 0) & (col < h.shape[1])
    out = np.zeros(mat_id.shape[0], bool)
    out[on] = h[np.flatnonzero(on), col[on]] >= 1.0
    return out


def set_failed(table, mat_id, history, mask) -> None:
    """Make the points ``mask`` (N,) bool failed, in place in ``history`` (N, n_history), as their
    law leaves a point that failed (no energy is released: the point was never intact): J2 D = 1;
    the mortar fully released along all three axes (Ω = I, so every crack is open in tension and
    closes in compression); the brittle law d = 1. Raises ValueError naming the law where a
    masked point's law cannot fail."""
    from . import MaterialTable

    table = MaterialTable.of(table)
    mat_id = np.asarray(mat_id, np.int64)
    mask = np.asarray(mask, bool)
    col = damage_columns(table)[mat_id]
    bad = mask & (col < 0)
    if bad.any():
        m = table.materials[int(mat_id[np.flatnonzero(bad)[0]])]
        raise ValueError(f"failed: a {m.law!r} material cannot fail; initially failed points "
                         "need a law with a failed state (j2, mortar, brittle)")
    for k, m in enumerate(table.materials):
        sel = np.flatnonzero(mask & (mat_id == k))
        if not sel.size:
            continue
        if m.law == "mortar":
            for c in range(3):  # Ω = I in the Voigt columns (xx, yy, zz, yz, xz, xy)
                history[sel, _mortar.H_OMEGA + c] = 1.0
            history[sel, _mortar.H_RELEASED] = 1.0
        history[sel, damage_column(m)] = 1.0
