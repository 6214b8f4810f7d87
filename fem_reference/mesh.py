"""Structured meshes of the scenes (scikit-fem) and the elements on them.

Element choice (:func:`element_for`):

- 2-D: biquadratic 9-node Lagrange quadrilaterals (``ElementQuad2``) with 3×3 Gauss points — they
  do not shear-lock in bending, unlike bilinear quadrilaterals (notes.md: ~3 % on the plate
  period).
- 3-D: trilinear hexahedra (``ElementHex1``, 2×2×2 Gauss points) for homogeneous states (the
  ss-curve block), where neither shear nor volumetric locking can arise; triquadratic 27-node
  hexahedra (``ElementHex2``, ``order=2``) for everything that bends — trilinear hexahedra
  shear-lock in bending (tests/test_fem_3d.py). Quadrature for the 27-node element: 3×3×3 Gauss
  (scikit-fem ``intorder=4``), the rule that integrates the stiffness of an affine element exactly
  (its integrand has degree 4 per direction); 2×2×2 would leave spurious zero-energy modes and
  tensor-product rules never use fewer than 2 points per direction, so there is no cheaper rule.

Against volumetric locking (nearly incompressible or plastic flow) the quadratic elements take the
F-bar option of :mod:`fem_reference.assembly` (J projected on linear polynomials: Q2–P1).

Meshes of unions of axis-aligned boxes (:func:`boxes_mesh`, e.g. a beam on a block): a
tensor-product grid whose lines include every box face, elements whose centroid lies outside the
union dropped; the element size from a resolution (:func:`grid_lines`).
"""
from __future__ import annotations


import numpy as np
import skfem


def rectangle(L: float, H: float, n_H: int, aspect: float = 1.0) -> skfem.MeshQuad:
    """0 ≤ X ≤ L, −H/2 ≤ Y ≤ H/2 with ``n_H`` elements across H and elements of width/height
    about ``aspect``."""
    n_L = max(1, int(round(n_H * L / (H * aspect))))
    return skfem.MeshQuad.init_tensor(np.linspace(0.0, L, n_L + 1),
                                      np.linspace(-H / 2, H / 2, n_H + 1))


def quarter_ring(a: float, b: float, n_r: int, n_theta: int) -> skfem.MeshQuad2:
    """The quarter annulus a ≤ R ≤ b, 0 ≤ Θ ≤ π/2 with ``n_r`` × ``n_theta`` elements, uniform
    in (R, Θ). Quadratic geometry (MeshQuad2: the mid-side and centre nodes are mapped too), so
    that the biquadratic elements are isoparametric and the circular edges are represented to
    O(h³) (the area of 4 × 8 elements with b/a = 2 is within 5e-5 of π(b² − a²)/4)."""
    m = skfem.MeshQuad2.from_mesh(skfem.MeshQuad.init_tensor(np.linspace(a, b, n_r + 1),
                                                             np.linspace(0.0, np.pi / 2, n_theta + 1)))
    return m.morphed(lambda x: x[0] * np.cos(x[1]), lambda x: x[0] * np.sin(x[1]))


def quarter_ring_3d(a: float, b: float, t: float, n_r: int, n_theta: int,
                    n_z: int = 1) -> skfem.MeshHex2:
    """The quarter of a thick-walled tube a ≤ R ≤ b, 0 ≤ Θ ≤ π/2, 0 ≤ Z ≤ t, ``n_r`` × ``n_theta``
    × ``n_z`` elements uniform in (R, Θ, Z), with quadratic geometry (MeshHex2, for the 27-node
    element: isoparametric, circles to O(h³))."""
    m = skfem.MeshHex2.from_mesh(skfem.MeshHex.init_tensor(
        np.linspace(a, b, n_r + 1), np.linspace(0.0, np.pi / 2, n_theta + 1),
        np.linspace(0.0, t, n_z + 1)))
    return m.morphed(lambda x: x[0] * np.cos(x[1]), lambda x: x[0] * np.sin(x[1]),
                     lambda x: x[2])


def block(a: float, n: int) -> skfem.MeshHex:
    """The cube [0, a]³ with ``n`` elements per edge."""
    x = np.linspace(0.0, a, n + 1)
    return skfem.MeshHex.init_tensor(x, x, x)


def box(lo, hi, n) -> skfem.MeshHex | skfem.MeshQuad:
    """The box lo ≤ X ≤ hi (2 or 3 coordinates) with n[i] elements along axis i (an int: the
    same along every axis)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    n = np.broadcast_to(np.asarray(n, dtype=int), lo.shape)
    lines = [np.linspace(lo[i], hi[i], n[i] + 1) for i in range(len(lo))]
    return _tensor(lines)


def tensor_mesh(lines) -> skfem.MeshQuad | skfem.MeshHex:
    """The tensor-product mesh of the grid ``lines`` (one increasing array per axis, 2 or 3)."""
    return _tensor([np.asarray(ln, dtype=float) for ln in lines])


def _tensor(lines):
    if len(lines) == 2:
        return skfem.MeshQuad.init_tensor(*lines)
    if len(lines) == 3:
        return skfem.MeshHex.init_tensor(*lines)
    raise ValueError(f"lines: 2 or 3 axes, got {len(lines)}")


def element_size(length: float, resolution: float) -> float:
    """The element size h = length/resolution (``resolution`` elements across ``length``, m)."""
    if not (length > 0 and resolution > 0):
        raise ValueError(f"resolution: {resolution} across length {length} is not allowed; "
                         "both must be > 0")
    return length / resolution


def grid_lines(boxes, h: float) -> list[np.ndarray]:
    """Per axis, the grid lines of a tensor grid whose lines include every face of ``boxes``
    (a sequence of (lo, hi) pairs of 2 or 3 coordinates) and whose spacing is about h: each gap
    between consecutive faces is cut into max(1, round(gap/h)) equal intervals."""
    boxes = [(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)) for lo, hi in boxes]
    if not boxes:
        raise ValueError("boxes: at least one box is needed")
    d = len(boxes[0][0])
    for lo, hi in boxes:
        if lo.shape != (d,) or hi.shape != (d,) or not np.all(hi > lo):
            raise ValueError(f"boxes: each box is (lo, hi) with {d} coordinates and hi > lo")
    if not h > 0:
        raise ValueError(f"h: {h} m is not allowed; the element size must be > 0")
    lines = []
    for i in range(d):
        faces = np.unique(np.concatenate([[lo[i], hi[i]] for lo, hi in boxes]))
        # faces closer than 1e-12 of the extent are one face
        ext = faces[-1] - faces[0]
        faces = faces[np.concatenate([[True], np.diff(faces) > 1e-12 * ext])]
        pts = [faces[:1]]
        for f0, f1 in zip(faces[:-1], faces[1:]):
            n = max(1, int(round((f1 - f0) / h)))
            pts.append(np.linspace(f0, f1, n + 1)[1:])
        lines.append(np.concatenate(pts))
    return lines


def in_boxes(x: np.ndarray, boxes) -> np.ndarray:
    """bool (n,): the points x (d, n) inside (or on) at least one of ``boxes``."""
    x = np.asarray(x, dtype=float)
    inside = np.zeros(x.shape[1], dtype=bool)
    for lo, hi in boxes:
        lo, hi = np.asarray(lo, dtype=float)[:, None], np.asarray(hi, dtype=float)[:, None]
        inside |= np.all((x >= lo) & (x <= hi), axis=0)
    return inside


def boxes_mesh(boxes, h: float, inside=None):
    """Structured mesh (MeshHex in 3-D, MeshQuad in 2-D) of the union of axis-aligned ``boxes``
    ((lo, hi) pairs): the tensor grid of :func:`grid_lines`, restricted to the elements whose
    centroid lies in the union, unused vertices removed. Every box face is a grid plane, so the
    union is meshed exactly and conformingly.

    ``inside(x (d, n)) -> bool (n,)``, when given, replaces the union as the test on the element
    centroids: the boxes then only place the grid lines (e.g. the bounding boxes of shapes that
    are not unions of boxes — a staircase approximation of their boundary — or the boxes of
    several regions with a held one left out)."""
    lines = grid_lines(boxes, h)
    full = _tensor(lines)
    centroids = full.p[:, full.t].mean(axis=1)
    test = (lambda c: in_boxes(c, boxes)) if inside is None else inside
    keep = np.flatnonzero(np.asarray(test(centroids), dtype=bool))
    if not len(keep):
        raise ValueError("inside: no element centroid lies in the body")
    if len(keep) == full.t.shape[1]:
        return full
    return full.restrict(keep)


def beam_on_block(L: float, B: float, H: float, block_size, h: float):
    """A 3-D cantilever L × B × H (X from 0 to L, centred on Y = 0 and Z = 0) on a block
    [−a, 0] × [−b/2, b/2] × [−c/2, c/2] with ``block_size`` = (a, b, c): the union of two boxes
    (:func:`boxes_mesh`). Returns (mesh, boxes)."""
    a, b, c = block_size
    boxes = [((0.0, -B / 2, -H / 2), (L, B / 2, H / 2)),
             ((-a, -b / 2, -c / 2), (0.0, b / 2, c / 2))]
    return boxes_mesh(boxes, h), boxes


def element_for(mesh, order: int | None = None) -> tuple[skfem.Element, int]:
    """The scalar element and the quadrature order (scikit-fem ``intorder``) used on ``mesh``:
    MeshQuad/MeshQuad2 → Q9 with 3×3 Gauss (``order=1``: Q4 with 2×2); MeshHex → Hex8 with 2×2×2
    Gauss (``order=2``: Hex27 with 3×3×3); MeshHex2 → Hex27 with 3×3×3 (module docstring)."""
    if order not in (None, 1, 2):
        raise ValueError(f"order: {order} is not one of None, 1, 2")
    if isinstance(mesh, skfem.MeshQuad2):
        if order == 1:
            raise ValueError("order: a quadratic-geometry mesh takes order 2")
        return skfem.ElementQuad2(), 4
    if isinstance(mesh, skfem.MeshQuad):
        return (skfem.ElementQuad1(), 2) if order == 1 else (skfem.ElementQuad2(), 4)
    if isinstance(mesh, skfem.MeshHex2):
        if order == 1:
            raise ValueError("order: a quadratic-geometry mesh takes order 2")
        return skfem.ElementHex2(), 4
    if isinstance(mesh, skfem.MeshHex):
        return (skfem.ElementHex2(), 4) if order == 2 else (skfem.ElementHex1(), 2)
    raise ValueError(f"mesh: {type(mesh).__name__} is not supported (MeshQuad or MeshHex)")


def vtk_grid(mesh):
    """The mesh's vertices and corner connectivity as a pyvista ``UnstructuredGrid`` (VTK_QUAD in
    2-D, VTK_HEXAHEDRON in 3-D; z = 0 in 2-D) for field output — the vertex values of a Lagrange
    field are its nodal values there (the higher-order nodes are not drawn)."""
    import pyvista as pv

    pts = np.asarray(mesh.p.T, dtype=float)
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    corners = np.asarray(mesh.t[: (4 if mesh.dim() == 2 else 8)].T, dtype=np.int64)
    kind = pv.CellType.QUAD if mesh.dim() == 2 else pv.CellType.HEXAHEDRON
    cells = np.column_stack([np.full(len(corners), corners.shape[1]), corners]).ravel()
    return pv.UnstructuredGrid(cells, np.full(len(corners), kind, dtype=np.uint8), pts)


# ------------------------------------------------------------------------------------------------
# Field output
# ------------------------------------------------------------------------------------------------

def mesh_series(folder, name: str, disc):
    """``add(t, u, v=None)`` writing the mesh (vertex ``displacement`` and, when given,
    ``velocity``) as a frame of the ParaView series ``name`` (.pvd + .vtu) in ``folder``."""
    from workbench.fields import FieldSeries

    series = FieldSeries(folder, name)
    grid = vtk_grid(disc.basis.mesh)
    nodal = disc.basis.nodal_dofs  # (d, n_vertices): the vertex DOFs of each component

    def add(t, u, v=None):
        data = dict(displacement=u[nodal].T)
        if v is not None:
            data["velocity"] = v[nodal].T
        series.add(t, grid=grid, **data)

    return add


def mesh_snapshots(folder, name: str, disc, n_steps: int, frames: int):
    """``snapshot(step, t, u, v)`` for :func:`fem_reference.dynamic.newmark`: about ``frames``
    frames of :func:`mesh_series` over ``n_steps`` steps, the last step always."""
    from workbench.fields import check_frames

    every = max(1, -(-int(n_steps) // check_frames(frames)))
    add = mesh_series(folder, name, disc)

    def snapshot(step, t, u, v):
        if step % every == 0 or step == n_steps:
            add(t, u, v)

    return snapshot
