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


def snapshot_png(vtk_file, png, scalars: str | None = None, title: str = "",
                 label: str | None = None, axes: tuple[str, str] | None = None) -> Path | None:
    """Render one field file to PNG off-screen; ``None`` where this machine cannot render.

    ``label``: the scalar bar's title (default: ``scalars``), e.g. with units; ``axes``: titles of
    the x and y axes (e.g. ``("x [m]", "y [m]")``), drawn with their bounds and ticks."""
    ok, _ = can_render()
    if not ok:
        return None
    import pyvista as pv

    mesh = pv.read(str(vtk_file))
    plane = view_plane(mesh.bounds)
    if plane != (0, 1):  # a 3-D body seen from the side: its two longest axes become x and y
        mesh = mesh.copy()
        mesh.points = mesh.points[:, [*plane, 3 - sum(plane)]]
        if axes is not None:
            axes = tuple(f"{'xyz'[k]} [m]" for k in plane)
    pl = pv.Plotter(off_screen=True, window_size=(900, 420))
    kw = dict(render_points_as_spheres=True, point_size=6) if isinstance(mesh, pv.PolyData) else {}
    bar = dict(title=label if label is not None else (scalars or ""))
    if axes is not None:
        bar.update(vertical=True, position_x=0.86, position_y=0.15, height=0.7, width=0.08)
    pl.add_mesh(mesh, scalars=scalars, cmap="viridis", scalar_bar_args=bar, **kw)
    if title:
        pl.add_text(title, font_size=10)
    pl.view_xy()
    if axes is not None:
        pl.show_bounds(xtitle=axes[0], ytitle=axes[1], ztitle="", show_zaxis=False,
                       location="outer", font_size=10, use_2d=True, fmt="%.3g",
                       n_xlabels=5, n_ylabels=3)
        _fit_xy(pl, mesh.bounds, window=(900, 420))
    pl.screenshot(str(png))
    pl.close()
    return Path(png)


def view_plane(bounds) -> tuple[int, int]:
    """The two axes (in order) a snapshot shows: the two of largest extent of ``bounds`` (xmin,
    xmax, ymin, ymax, zmin, zmax): (0, 1) for a 2-D body, e.g. (0, 2) for a beam along x, deep in
    z and narrow in y (the RC beam's quarter model seen from its side)."""
    ext = [bounds[2 * k + 1] - bounds[2 * k] for k in range(3)]
    return tuple(sorted(sorted(range(3), key=lambda k: -ext[k])[:2]))


def _fit_xy(pl, bounds, window, left: float = 0.1, right: float = 0.8,
            margin: float = 0.18) -> None:
    """Parallel projection onto the xy plane with the body filling the window between the
    fractions ``left`` and ``right`` of its width (axis labels to the left, the scalar bar to the
    right) and ``margin`` of its height kept free above and below."""
    x0, x1, y0, y1 = bounds[:4]
    w, h = max(x1 - x0, 1e-30), max(y1 - y0, 1e-30)
    ratio = window[0] / window[1]
    half_h = 0.5 * max(h / (1.0 - 2 * margin), w / (0.95 * (right - left) * ratio))
    cx = 0.5 * (x0 + x1) + (1.0 - left - right) * half_h * ratio
    cy = 0.5 * (y0 + y1)
    pl.enable_parallel_projection()
    cam = pl.camera
    cam.focal_point = (cx, cy, 0.0)
    cam.position = (cx, cy, 10.0 * max(w, h))
    cam.up = (0.0, 1.0, 0.0)
    cam.parallel_scale = half_h


# ------------------------------------------------------------------------------------------------
# Snapshots of the particle drivers
# ------------------------------------------------------------------------------------------------

DEFAULT_FRAMES = 20
"""Frames written over a run (besides the initial state) unless ``field_frames`` says otherwise."""


def series_name(scene_name: str, method: str, resolution: int) -> str:
    """The name of a run's field series, e.g. ``plate_csph_H10`` (resolution: r intervals across the scene's length, spacing H/r)."""
    return f"{scene_name}_{method}_H{int(resolution)}"


def check_frames(frames) -> int:
    if not (isinstance(frames, (int, np.integer)) and not isinstance(frames, bool) and frames >= 1):
        raise ValueError(f"field_frames: {frames!r} is not allowed; an integer >= 1")
    return int(frames)


def particle_point_data(material, X, x, v, F=None, history=None, sigma=None, mat_id=None,
                        region=None) -> dict:
    """Point data of one particle snapshot: ``displacement`` x − X (m), ``velocity`` (m/s),
    ``stress`` (Cauchy, 3×3, Pa; plane strain keeps σ_zz), ``von_mises`` (Pa), where a J2
    material is present ``plastic_strain`` (equivalent plastic strain ε_p, -), and where a
    material can fail ``damage`` (in [0, 1], failed at 1, any law:
    :func:`workbench.materials.failure.damage`); ``region`` (the region index of each particle)
    when given.

    ``material``: a Material or a MaterialTable (then ``mat_id`` gives each particle's row). The
    Cauchy stress is ``sigma`` when the method carries it (classic SPH), else it is evaluated from
    the deformation gradients F (N, 3, 3) and the committed ``history`` by the shared material
    routine (no new stress state is created; the history is not changed)."""
    from .materials import HIST_DAMAGE, HIST_EPS_P, MaterialTable, evaluate
    from .materials.failure import can_fail, damage

    table = MaterialTable.of(material)
    x = np.asarray(x, dtype=float)
    d = x.shape[1]
    if sigma is None:
        if F is None:
            raise ValueError("particle_point_data: give F or sigma")
        sigma = evaluate(table, np.ascontiguousarray(F), history, stress="sigma",
                         mat_id=mat_id)["stress"]
    s = np.asarray(sigma, dtype=float)
    if s.shape[1] < 3:  # a 2×2 in-plane stress: no σ_zz known
        full = np.zeros((s.shape[0], 3, 3))
        full[:, :s.shape[1], :s.shape[2]] = s
        s = full
    dev = s - np.einsum("nii->n", s)[:, None, None] / 3.0 * np.eye(3)
    out = dict(displacement=x - np.asarray(X, dtype=float)[:, :d], velocity=np.asarray(v, dtype=float),
               stress=s, von_mises=np.sqrt(1.5 * np.einsum("nij,nij->n", dev, dev)))
    if (any(m.law == "j2" for m in table.materials) and history is not None
            and np.shape(history)[1] > HIST_DAMAGE):
        h = np.asarray(history)
        j2 = np.array([m.law == "j2" for m in table.materials])[
            np.zeros(len(x), np.int64) if mat_id is None else np.asarray(mat_id)]
        out["plastic_strain"] = np.where(j2, h[:, HIST_EPS_P], 0.0)
        out["damage"] = np.where(j2, h[:, HIST_DAMAGE], 0.0)
    if can_fail(table) and history is not None and np.shape(history)[1] > 0:
        out["damage"] = damage(table, np.zeros(len(x), np.int64) if mat_id is None else mat_id,
                               history)
    if region is not None:
        out["region"] = np.asarray(region, dtype=float)
    return out


class Snapshots:
    """Field output of a particle driver's time loop: a :class:`FieldSeries` written every
    ``every`` steps from Python, between the calls of the compiled loop (never inside it).

    The drivers advance in chunks of ``chunk`` steps (their recording interval); a snapshot is due
    every ``every`` steps, a multiple of ``chunk`` chosen so that about ``frames`` frames cover the
    ``n_steps`` of the run — so asking for fields changes neither the chunks nor any result. Call
    ``snap(steps_done)`` after each chunk, ``snap(0)`` before the loop and ``snap(steps, final=True)``
    after it (the final state is always written). ``state()`` returns dict(t, x, v and F + history
    or sigma); see :func:`particle_point_data`."""

    def __init__(self, folder, name: str, X, material, state, n_steps: int, chunk: int,
                 frames: int = DEFAULT_FRAMES):
        frames = check_frames(frames)
        self.series = FieldSeries(folder, name)
        self.X = np.asarray(X, dtype=float)
        self.material = material
        self.state = state
        chunk = max(1, int(chunk))
        n_chunks = max(1, -(-int(n_steps) // chunk))
        self.every = chunk * max(1, -(-n_chunks // frames))
        self.last = None

    @classmethod
    def open(cls, folder, *args, **kwargs) -> "Snapshots | None":
        """``None`` when ``folder`` is None (no field output requested)."""
        return None if folder is None else cls(folder, *args, **kwargs)

    def __call__(self, steps_done: int, final: bool = False) -> Path | None:
        if steps_done == self.last or not (final or steps_done % self.every == 0):
            return None
        self.last = steps_done
        st = self.state()
        data = particle_point_data(self.material, self.X, st["x"], st["v"], st.get("F"),
                                   st.get("history"), st.get("sigma"), st.get("mat_id"),
                                   st.get("region"))
        return self.series.add(st["t"], st["x"], **data)


def series_frames(pvd) -> list[tuple[float, Path]]:
    """(time, file) of every frame listed in a ``.pvd`` collection."""
    import xml.etree.ElementTree as ET

    pvd = Path(pvd)
    return [(float(e.get("timestep")), pvd.parent / e.get("file"))
            for e in ET.parse(pvd).getroot().iter("DataSet")]


def render_series(pvd, png, scalars: str = "von_mises", label: str = "von Mises stress [Pa]",
                  title: str = "", time_label: str = "t = {:.4g} s") -> tuple[Path | None, str]:
    """Snapshot of the frame of largest displacement of a particle series (deformed positions,
    coloured by ``scalars``, the scalar bar titled ``label``), with the axes in metres and the
    frame's time written with ``time_label``. Returns (png or None, reason when None)."""
    ok, why = can_render()
    if not ok:
        return None, why
    import pyvista as pv

    frames = series_frames(pvd)
    if not frames:
        return None, f"{Path(pvd).name} lists no frames"
    umax = [float(np.abs(pv.read(str(f)).point_data["displacement"]).max()) for _, f in frames]
    t, f = frames[int(np.argmax(umax))]
    text = f"{title}, {time_label.format(t)}" if title else time_label.format(t)
    return snapshot_png(f, png, scalars=scalars, title=text, label=label, axes=("x [m]", "y [m]")), ""
