"""PNG previews of the gmsh model in the current session."""

import gmsh
import numpy as np

from pinbore.core.figures import offscreen_pyvista, plt, save_image, save_png


def _triangles_2d():
    """Node coordinates and triangle connectivity (indices into them) of the 2D mesh."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xy = coords.reshape(-1, 3)[:, :2]
    index = np.zeros(int(tags.max()) + 1, dtype=int)
    index[tags.astype(int)] = np.arange(tags.size)
    _, nodes = gmsh.model.mesh.getElementsByType(2)
    return xy, index[nodes.astype(int)].reshape(-1, 3)


def preview_2d(path, geometry, direction_deg: float, zoom_half_angle: float) -> None:
    """The whole model beside a zoom on the contact arc (±zoom_half_angle rad)."""
    xy, triangles = _triangles_2d()
    fig, axes = plt.subplots(1, 3, figsize=(15, 5))
    r, a = geometry.bore_radius, np.radians(direction_deg)
    views = [("whole model", geometry.housing_radius),
             ("pin and bore", 1.15 * r),
             ("contact arc", r * max(np.sin(min(zoom_half_angle, np.pi / 2)), 0.02))]
    for ax, (title, half) in zip(axes, views):
        centre = (0.0, 0.0) if half > r else (r * np.cos(a), r * np.sin(a))
        ax.triplot(1e3 * xy[:, 0], 1e3 * xy[:, 1], triangles, lw=0.25, color="0.2")
        ax.set_xlim(1e3 * (centre[0] - half), 1e3 * (centre[0] + half))
        ax.set_ylim(1e3 * (centre[1] - half), 1e3 * (centre[1] + half))
        ax.set_aspect("equal")
        ax.set_title(title)
        ax.set_xlabel("x (mm)")
    axes[0].set_ylabel("y (mm)")
    fig.suptitle(f"{triangles.shape[0]} triangles, {xy.shape[0]} nodes; load at {direction_deg:g} deg")
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    save_png(fig, path)


def preview_3d(path) -> None:
    """Off-screen pyvista rendering of the 3D mesh's surface, pin and housing cut open."""
    pyvista = offscreen_pyvista()
    tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(tags.max()) + 1, dtype=int)
    index[tags.astype(int)] = np.arange(tags.size)
    _, nodes = gmsh.model.mesh.getElementsByType(4)
    tets = index[nodes.astype(int)].reshape(-1, 4)
    cells = np.hstack([np.full((tets.shape[0], 1), 4), tets]).ravel()
    grid = pyvista.UnstructuredGrid(cells, np.full(tets.shape[0], pyvista.CellType.TETRA),
                                    coords.reshape(-1, 3))
    half = grid.clip(normal="x", origin=(0, 0, 0))
    plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 900))
    plotter.add_mesh(half.extract_surface(algorithm="dataset_surface"), show_edges=True, color="lightsteelblue",
                     edge_color="black", line_width=0.3)
    plotter.add_text(f"{tets.shape[0]} tetrahedra, {coords.size // 3} nodes (cut at x = 0)",
                     font_size=10)
    plotter.camera_position = "iso"
    save_image(plotter.screenshot(return_img=True), path)
    plotter.close()
