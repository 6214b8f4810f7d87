"""Field output for ParaView: particle and mesh fields as VTK time series written with pyvista.

:class:`FieldSeries` writes one ``.vtp`` (particles) or ``.vtu`` (meshes) per snapshot and keeps a
``.pvd`` collection file listing them with their times (pyvista has no ``.pvd`` writer; it is a short
XML file, written atomically after every snapshot so that an interrupted run leaves a readable
series). :func:`snapshot_png` renders a series' last frame off-screen where the machine can, and
returns ``None`` with a reason where it cannot.
"""
from __future__ import annotations

import os
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from .results import atomic_write_text


class FieldSeries:
    """A time series of particle or mesh fields: ``series.add(t, points, u=…, sigma=…)``.

    ``points``: (N, 2) or (N, 3) current positions (2-D is padded with z = 0); point data arrays of
    shape (N,), (N, d) or (N, d, d) (tensors are flattened to 9 components, ParaView's convention).
    For a mesh, pass ``cells`` as a pyvista ``UnstructuredGrid`` instead of ``points``.
    """

    def __init__(self, folder, name: str):
        self.folder = Path(folder)
        self.name = name
        self.entries: list[tuple[float, str]] = []
        self.folder.mkdir(parents=True, exist_ok=True)

    @property
    def pvd(self) -> Path:
        return self.folder / f"{self.name}.pvd"

    def add(self, time: float, points=None, grid=None, **data) -> Path:
        import pyvista as pv

        if grid is None:
            pts = np.asarray(points, dtype=float)
            if pts.shape[1] == 2:
                pts = np.column_stack([pts, np.zeros(len(pts))])
            mesh = pv.PolyData(pts)
            ext = "vtp"
        else:
            mesh = grid.copy()
            ext = "vtu"
        n = mesh.n_points
        for key, val in data.items():
            a = np.asarray(val, dtype=float)
            if a.shape[0] != n:
                raise ValueError(f"{key}: {a.shape[0]} values for {n} points")
            if a.ndim == 2 and a.shape[1] == 2:
                a = np.column_stack([a, np.zeros(n)])
            elif a.ndim == 3:
                d = a.shape[1]
                full = np.zeros((n, 3, 3))
                full[:, :d, :d] = a
                a = full.reshape(n, 9)
            mesh.point_data[key] = a
        fname = f"{self.name}_{len(self.entries):05d}.{ext}"
        tmp = self.folder / f".{fname}.tmp.{ext}"
        mesh.save(tmp)
        os.replace(tmp, self.folder / fname)
        self.entries.append((float(time), fname))
        self._write_pvd()
        return self.folder / fname

    def _write_pvd(self) -> None:
        rows = "\n".join(f'    <DataSet timestep={quoteattr(repr(t))} part="0" file={quoteattr(f)}/>'
                         for t, f in self.entries)
        atomic_write_text(self.pvd, '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                                    f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")


def can_render() -> tuple[bool, str]:
    """Whether pyvista can render off-screen here, and why not."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    try:
        import pyvista as pv

        pl = pv.Plotter(off_screen=True, window_size=(64, 64))
        pl.add_mesh(pv.Sphere())
        pl.screenshot(return_img=True)
        pl.close()
        return True, ""
    except Exception as err:  # no EGL/OSMesa: say so instead of failing
        return False, f"off-screen rendering unavailable ({type(err).__name__}: {err})"


def snapshot_png(vtk_file, png, scalars: str | None = None, title: str = "") -> Path | None:
    """Render one field file to PNG off-screen; ``None`` where this machine cannot render."""
    ok, _ = can_render()
    if not ok:
        return None
    import pyvista as pv

    mesh = pv.read(str(vtk_file))
    pl = pv.Plotter(off_screen=True, window_size=(900, 420))
    kw = dict(render_points_as_spheres=True, point_size=6) if isinstance(mesh, pv.PolyData) else {}
    pl.add_mesh(mesh, scalars=scalars, cmap="viridis", scalar_bar_args=dict(title=scalars or ""), **kw)
    if title:
        pl.add_text(title, font_size=10)
    pl.view_xy()
    pl.screenshot(str(png))
    pl.close()
    return Path(png)
