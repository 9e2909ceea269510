"""`pinbore modes SCENE --out DIR`: a body's FE model reduced to a flexible body
(fem.modes.reduction); write DIR/body.npz (fem.modes.file: what a mechanism reads),
DIR/modes.json (frequencies, the reduction's error against the whole model, mass, times) and
DIR/mode_shapes.png."""

import platform
import sys
import time
from pathlib import Path

import numpy as np
import pydantic
from tqdm import tqdm

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.figures import offscreen_pyvista, plt, save_image, save_png
from pinbore.core.output import atomic_directory
from pinbore.fem.modes import file as body_file
from pinbore.fem.modes.scene import ModesScene

PICTURED = 6   # modes drawn in mode_shapes.png


def run(scene_path, out, scene: ModesScene | None = None) -> int:
    from mpi4py import MPI   # noqa: PLC0415

    from pinbore.fem.modes import reduction   # noqa: PLC0415 (DOLFINx: after the scene is valid)

    if MPI.COMM_WORLD.size > 1:
        raise InputError("pinbore modes runs on one MPI rank (a body's reduction is serial); "
                         "run it without mpiexec")
    scene = scene or scenes.load(ModesScene, scene_path)
    start = time.perf_counter()
    with atomic_directory(out, MPI.COMM_SELF) as tmp:
        with tqdm(total=4, desc=f"modes {Path(scene_path).stem}", unit="step", disable=None,
                  leave=False) as bar:
            reduced = reduction.reduce(scene, progress=bar)
        body = body_of(reduced, scene_path)
        body_file.write(tmp / body_file.BODY, body)
        summary = summarise(scene, scene_path, reduced, body, time.perf_counter() - start)
        mode_shapes(tmp / "mode_shapes.png", body)
        body_file.write_summary(tmp / body_file.SUMMARY, summary)
    f = ", ".join(f"{v:.4g}" for v in summary.frequencies_Hz[:6])
    print(f"pinbore modes: {scene_path}: {reduced.dofs} dofs -> {body.modes} modes ({f} Hz) "
          f"in {summary.wall_time_s['total']:.1f} s", file=sys.stderr)
    return 0


def body_of(reduced, scene_path) -> body_file.ReducedBody:
    return body_file.ReducedBody(
        scene=Path(scene_path).name, scene_sha256=body_file.file_hash(scene_path),
        dim=reduced.dim, mass=reduced.mass, centre=reduced.centre, omega=reduced.omega,
        psi=reduced.psi, nodes=reduced.X, cells=reduced.cells,
        second_moments=reduced.second_moments, s=reduced.s, S=reduced.S,
        translation_coupling=reduced.translation_coupling, stiffening=reduced.stiffening,
        interfaces=tuple(reduced.interfaces), interface_centres=reduced.interface_centres,
        interface_translation=reduced.interface_translation,
        interface_rotation=reduced.interface_rotation,
        fixed_interface_omega=reduced.fixed_interface_omega, full_omega=reduced.full_omega)


def summarise(scene, scene_path, reduced, body, total) -> body_file.ModesSummary:
    """modes.json's record; a reduced body that fails its physical checks (the record's rules:
    frequencies positive and finite, the mass positive, the modes in the mean-axis frame) is
    an InputError naming them: it is not written."""
    try:
        return _summary(scene, scene_path, reduced, body, total)
    except pydantic.ValidationError as err:
        from pinbore.fem.modes.reduction import unresolved   # noqa: PLC0415 (DOLFINx)

        wrong = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in err.errors()[:3])
        raise unresolved(scene, f"its record fails {wrong}; nothing written") from None


def _summary(scene, scene_path, reduced, body, total) -> body_file.ModesSummary:
    hz = reduced.omega / (2 * np.pi)
    full = reduced.full_omega / (2 * np.pi)
    m = min(full.size, hz.size)
    seconds = dict(reduced.seconds, total=total)
    return body_file.ModesSummary(
        scene_file=str(scene_path), scene=scene.model_dump(mode="json"), dofs=reduced.dofs,
        nodes=reduced.X.shape[0], cells=reduced.cells.shape[0], mass_kg=reduced.mass,
        centre_m=reduced.centre.tolist(),
        inertia_kg_m2=body.inertia.tolist(),
        frequencies_Hz=hz.tolist(),
        fixed_interface_frequencies_Hz=(reduced.fixed_interface_omega / (2 * np.pi)).tolist(),
        full_frequencies_Hz=full.tolist(), reduction_error=(hz[:m] / full[:m] - 1).tolist(),
        mean_axis_residual=max(body_file.mean_axis_residuals(body)),
        rigid_residual=reduced.rigid_residual,
        wall_time_s=seconds,
        platform={"python": platform.python_version(), "machine": platform.machine()})


def deformed(body: body_file.ReducedBody, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The nodes moved by mode k scaled to a tenth of the body's size, and |u| of it."""
    u = body.psi[:, :, k]
    extent = np.ptp(body.nodes, axis=0).max()
    scale = 0.1 * extent / np.abs(u).max()
    return body.nodes + scale * u, np.linalg.norm(u, axis=1) * scale


def mode_shapes(path: Path, body: body_file.ReducedBody) -> None:
    """The first modes, drawn deformed over the undeformed body (grey)."""
    count = min(PICTURED, body.modes)
    if body.dim == 2:
        fig, axes = plt.subplots(count, 1, figsize=(9, 1.6 * count + 0.6), squeeze=False)
        triangles = body.cells[:, :3]
        for k, ax in enumerate(axes[:, 0]):
            x, magnitude = deformed(body, k)
            ax.triplot(body.nodes[:, 0], body.nodes[:, 1], triangles, lw=0.15, color="0.75")
            ax.tripcolor(x[:, 0], x[:, 1], triangles, magnitude, shading="gouraud", cmap="viridis")
            ax.set_aspect("equal")
            ax.set_axis_off()
            ax.set_title(f"mode {k + 1}: {body.omega[k] / (2 * np.pi):.5g} Hz", fontsize=9)
        fig.suptitle(f"{body.scene}: the reduced body's free modes (floating frame)", fontsize=10)
        save_png(fig, path, layout=True)
        return
    pyvista = offscreen_pyvista()
    tets = body.cells[:, :4]
    cells = np.hstack([np.full((tets.shape[0], 1), 4), tets]).ravel()
    rows = 2 if count > 3 else 1
    columns = (count + rows - 1) // rows
    plotter = pyvista.Plotter(off_screen=True, shape=(rows, columns),
                              window_size=(450 * columns, 380 * rows))
    types = np.full(tets.shape[0], pyvista.CellType.TETRA)
    undeformed = pyvista.UnstructuredGrid(cells, types, body.nodes).extract_surface(
        algorithm="dataset_surface")
    for k in range(count):
        plotter.subplot(k // columns, k % columns)
        x, magnitude = deformed(body, k)
        grid = pyvista.UnstructuredGrid(cells, types, x)
        grid.point_data["|u|"] = magnitude
        plotter.add_mesh(undeformed, color="lightgrey", opacity=0.25)
        plotter.add_mesh(grid.extract_surface(algorithm="dataset_surface"), scalars="|u|",
                         cmap="viridis", show_scalar_bar=False)
        plotter.add_text(f"mode {k + 1}: {body.omega[k] / (2 * np.pi):.5g} Hz", font_size=10)
        plotter.camera_position = "iso"
    save_image(plotter.screenshot(return_img=True), path)
    plotter.close()
