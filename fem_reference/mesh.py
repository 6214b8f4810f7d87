"""Structured meshes of the scenes (scikit-fem) and the elements on them.

Element choice: biquadratic 9-node Lagrange quadrilaterals (``ElementQuad2``) with 3×3 Gauss points
in 2-D — they do not shear-lock in bending, unlike bilinear quadrilaterals (notes.md: ~3 % on the
plate period); trilinear hexahedra with 2×2×2 Gauss points for the homogeneous 3-D block. Against
volumetric locking the 2-D element takes the F-bar option of :mod:`fem_reference.assembly`.
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


def block(a: float, n: int) -> skfem.MeshHex:
    """The cube [0, a]³ with ``n`` elements per edge."""
    x = np.linspace(0.0, a, n + 1)
    return skfem.MeshHex.init_tensor(x, x, x)


def element_for(mesh) -> tuple[skfem.Element, int]:
    """The scalar element and the quadrature order used on ``mesh``."""
    if isinstance(mesh, skfem.MeshQuad):
        return skfem.ElementQuad2(), 4  # 3×3 Gauss points
    if isinstance(mesh, skfem.MeshHex):
        return skfem.ElementHex1(), 2  # 2×2×2 Gauss points
    raise ValueError(f"mesh: {type(mesh).__name__} is not supported (MeshQuad or MeshHex)")


def vtk_grid(mesh):
    """The mesh's vertices and corner connectivity as a pyvista ``UnstructuredGrid`` (VTK_QUAD in
    2-D, VTK_HEXAHEDRON in 3-D; z = 0 in 2-D) for field output — the vertex values of a Lagrange
    field are its nodal values there (the mid-side and centre nodes of Q9 are not drawn)."""
    import pyvista as pv

    pts = np.asarray(mesh.p.T, dtype=float)
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    corners = np.asarray(mesh.t[: (4 if mesh.dim() == 2 else 8)].T, dtype=np.int64)
    kind = pv.CellType.QUAD if mesh.dim() == 2 else pv.CellType.HEXAHEDRON
    cells = np.column_stack([np.full(len(corners), corners.shape[1]), corners]).ravel()
    return pv.UnstructuredGrid(cells, np.full(len(corners), kind, dtype=np.uint8), pts)
