"""Files of an FE run: curve.csv, pressure.csv, result.json, fields (XDMF) and pictures
(2D: contact.png; 3D: pressure_map.png and axial_profile.png).

Forces, torques and work are per unit length in 2D and of the whole pin in 3D (a half model
counts twice); 3D half-angles are those of the section at the pin's middle. The columns of
curve.csv and pressure.csv, their units and formats are those of pinbore.fem.curve."""

import json
from pathlib import Path

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import dolfinx
import dolfinx.io
import numpy as np

from pinbore.core.figures import offscreen_pyvista, plt, save_image, save_png
from pinbore.fem import curve
from pinbore.fem.contact import OPEN, SLIP, STATE_NAMES, STICK, tributary_lengths
from pinbore.fem.post import angle_from, contact_length, half_angle, resultant_z


def curve_rows(run, direction_deg, contact, pivot_z, copies=1):
    """The rows of curve.csv (fields of pinbore.fem.curve.Curve), one per converged step; 3D
    with the tilt columns (pivot_z: the bore's mid-plane, copies: 2 for a half model)."""
    section = contact.mid_section()
    dissipated = 0.0
    for i, step in enumerate(run.steps, start=1):
        alpha = angle_from(direction_deg, step.contact.angle[section])
        touching = step.contact.status != OPEN
        stuck = np.count_nonzero(step.contact.status == STICK) / max(np.count_nonzero(touching), 1)
        dissipated += step.dissipated
        row = {"step": i, "stage": step.stage or curve.stage(step.point), "approach": step.point[0],
               "rotation": np.degrees(step.point[1]), "tangential_push": step.point[2],
               "force": step.force[0], "tangential_force": step.force[1],
               "friction_torque": step.torque,
               "half_angle": np.degrees(half_angle(alpha, step.contact.pressure[section])),
               "stick_fraction": stuck, "dissipated_work": dissipated,
               "plastic_work": step.plastic_work, "max_plastic_strain": step.max_plastic_strain,
               "residual_approach": step.residual_approach,
               "newton_iterations": step.newton_iterations,
               "uzawa_iterations": step.uzawa_iterations, "gap_violation": step.gap_violation}
        if contact.dim == 3:
            angles, levels = contact.pin_grid
            slack = 1e-9 * pivot_z   # levels are averaged node coordinates
            in_bore = (levels >= -slack) & (levels <= 2 * pivot_z + slack)
            pressure = step.contact.pressure.reshape(levels.size, angles.size)
            row |= {"tilt": np.degrees(step.point[3]), "tilt_moment": step.moment,
                    "resultant_z": resultant_z(step.force[0], step.moment, pivot_z),
                    "contact_length": contact_length(pressure[in_bore], levels[in_bore], copies)}
        yield row


def write_curve(path: Path, run, direction_deg, contact, pivot_z, copies=1) -> None:
    """One row per converged step (see the module docstring for the units)."""
    curve.write(path, contact.dim, curve_rows(run, direction_deg, contact, pivot_z, copies))


def pressure_rows(run, direction_deg, arc_half_angle, contact):
    """The rows of pressure.csv (fields of pinbore.fem.curve.Pressure): every step, the nodes
    of the refined arc by angle from the load (3D: by z, then angle)."""
    three_d = contact.dim == 3
    for i, step in enumerate(run.steps, start=1):
        c = step.contact
        alpha = angle_from(direction_deg, c.angle)
        keep = np.flatnonzero(np.abs(alpha) <= arc_half_angle)
        level = contact.pin_reference[keep, 2] if three_d else np.zeros(keep.size)
        for j in keep[np.lexsort((alpha[keep], level))]:
            row = {"step": i, "angle": np.degrees(alpha[j]), "pressure": c.pressure[j],
                   "shear": c.shear[j, 0], "state": STATE_NAMES[c.status[j]]}
            if three_d:
                row |= {"z": contact.pin_reference[j, 2], "shear_axial": c.shear[j, 1]}
            yield row


def write_pressure(path: Path, run, direction_deg, arc_half_angle, contact) -> None:
    """Nodal pressure, shear on the bore (along +theta; 3D: and +z) and stick/slip/open
    state on the refined arc (where contact can be), by angle from the load (3D: and by the
    axial position z of the node on the untilted pin, over the modelled length)."""
    curve.write_pressure(path, contact.dim,
                         pressure_rows(run, direction_deg, arc_half_angle, contact))


def write_result(path: Path, result: dict) -> None:
    path.write_text(json.dumps(result, indent=2, sort_keys=False) + "\n")


class FieldWriter:
    """Displacement, von Mises stress and contact pressure per converged step, for ParaView;
    with an elasto-plastic material also the equivalent plastic strain (cell means, DG0)."""

    def __init__(self, path: Path, elasticity, contact, material=None):
        mesh = elasticity.mesh
        self.material = material if material is not None and material.plastic else None
        self.u = dolfinx.fem.Function(elasticity.V, name="displacement")
        Q = dolfinx.fem.functionspace(mesh, ("DG", 0))
        self.von_mises = dolfinx.fem.Function(Q, name="von_mises")
        self.vm_expr = dolfinx.fem.Expression(elasticity.von_mises(self.u),
                                              Q.element.interpolation_points)
        self.plastic_strain = dolfinx.fem.Function(Q, name="equivalent_plastic_strain")
        self.cells = mesh.topology.index_map(mesh.topology.dim).size_local
        W = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
        self.pressure = dolfinx.fem.Function(W, name="contact_pressure")
        # gathered pin nodes -> local scalar dofs (same layout as the blocked vector space)
        local = elasticity.V.dofmap.index_map.global_to_local(contact.pin_nodes)
        self.mine = np.flatnonzero(local >= 0)
        self.local = local[self.mine]
        self.step = 0  # the XDMF "time" is the step number (the programme is not monotone in one)
        self.file = dolfinx.io.XDMFFile(mesh.comm, str(path), "w")
        self.file.write_mesh(mesh)

    def write(self, x, step):
        x.copy(self.u.x.petsc_vec)
        self.u.x.scatter_forward()
        shown = [self.u, self.von_mises, self.pressure]
        if self.material is None:
            self.von_mises.interpolate(self.vm_expr)
        else:   # the stress of the committed state (DG0: one value per cell)
            for f, name in ((self.von_mises, "von_mises"),
                            (self.plastic_strain, "equivalent_plastic_strain")):
                f.x.array[:self.cells] = self.material.cell_values(name)
                f.x.scatter_forward()
            shown.append(self.plastic_strain)
        self.pressure.x.array[:] = 0.0
        self.pressure.x.array[self.local] = step.contact.pressure[self.mine]
        self.step += 1
        for f in shown:
            self.file.write_function(f, float(self.step))

    def close(self):
        self.file.close()


def deformed_triangles(elasticity, u, magnify, pin_shift):
    """Cells of this rank drawn at X + pin_shift (pin only) + magnify (u - pin_shift)."""
    mesh = elasticity.mesh
    n_cells = mesh.topology.index_map(2).size_local
    X = mesh.geometry.x[mesh.geometry.dofmap[:n_cells], :2]
    disp = u.x.array.reshape(-1, 2)[elasticity.V.dofmap.list[:n_cells]]
    on_pin = np.isin(elasticity.V.dofmap.list[:n_cells], elasticity.pin_nodes)[..., None]
    rigid = np.where(on_pin, pin_shift, 0.0)
    return X + rigid + magnify * (disp - rigid)


def picture(path: Path, elasticity, x, run, scene, arc_half_angle, touch: float):
    """Deformed contact zone coloured by von Mises stress, beside the pressure profiles (and,
    with friction, the shear profiles with the stick / slip state of the last step); `touch`
    (m): the hub's travel to first touch, drawn unmagnified (the clearance, a worn joint's
    first touch)."""
    comm = elasticity.mesh.comm
    u = dolfinx.fem.Function(elasticity.V)
    x.copy(u.x.petsc_vec)
    u.x.scatter_forward()
    Q = dolfinx.fem.functionspace(elasticity.mesh, ("DG", 0))
    vm = dolfinx.fem.Function(Q)
    vm.interpolate(dolfinx.fem.Expression(elasticity.von_mises(u), Q.element.interpolation_points))
    g = scene.geometry
    last = run.steps[-1]
    direction = np.asarray(scene.load.direction)
    eps = half_angle(angle_from(scene.load.direction_deg, last.contact.angle), last.contact.pressure)
    view = 1.3 * g.bore_radius * max(np.sin(min(eps, np.pi / 2)), 0.02)
    magnify = 0.1 * view / max(last.approach, 1e-30)
    cells = deformed_triangles(elasticity, u, magnify, touch * direction)
    n_cells = cells.shape[0]
    gathered = comm.gather((cells, vm.x.array[:n_cells]), root=0)
    if comm.rank != 0:
        return
    cells = np.concatenate([c for c, _ in gathered])
    values = np.concatenate([v for _, v in gathered])
    friction = scene.contact.friction > 0
    fig, axes = plt.subplots(1, 3 if friction else 2, figsize=(19 if friction else 13, 5.5))
    ax, bx = axes[:2]
    centre = g.bore_radius * direction
    near = np.linalg.norm(cells.mean(axis=1) - centre, axis=1) < 2 * view
    tri = np.arange(3 * near.sum()).reshape(-1, 3)
    xy = 1e3 * cells[near].reshape(-1, 2)
    shown = ax.tripcolor(xy[:, 0], xy[:, 1], tri, facecolors=values[near] / 1e6,
                         cmap="viridis", edgecolors="none")
    fig.colorbar(shown, ax=ax, label="von Mises stress (MPa)")
    ax.set_xlim(1e3 * (centre[0] - view), 1e3 * (centre[0] + view))
    ax.set_ylim(1e3 * (centre[1] - view), 1e3 * (centre[1] + view))
    ax.set_aspect("equal")
    ax.set_title(f"deformed contact zone, deformation x{magnify:.3g}\n"
                 f"approach {last.approach:.3g} m, half-angle {np.degrees(eps):.1f} deg")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    for i, step in enumerate(run.steps, start=1):
        alpha = angle_from(scene.load.direction_deg, step.contact.angle)
        keep = np.abs(alpha) <= arc_half_angle
        order = np.argsort(alpha[keep])
        bx.plot(np.degrees(alpha[keep][order]), step.contact.pressure[keep][order] / 1e6,
                color=plt.cm.plasma(i / (len(run.steps) + 1)), lw=1)
    bx.set_xlabel("angle from load direction (deg)")
    bx.set_ylabel("contact pressure (MPa)")
    bx.set_title("pressure on the bore, every load step")
    bx.grid(alpha=0.3)
    if friction:
        shear_panel(axes[2], run, scene, arc_half_angle)
    save_png(fig, path, layout=True)


def shear_panel(ax, run, scene, arc_half_angle):
    """Shear on the bore at every step, the Coulomb bound +-mu p and the stick / slip nodes of
    the last step."""
    for i, step in enumerate(run.steps, start=1):
        alpha = angle_from(scene.load.direction_deg, step.contact.angle)
        keep = np.flatnonzero(np.abs(alpha) <= arc_half_angle)
        keep = keep[np.argsort(alpha[keep])]
        ax.plot(np.degrees(alpha[keep]), step.contact.shear[keep, 0] / 1e6,
                color=plt.cm.plasma(i / (len(run.steps) + 1)), lw=1)
    c = run.steps[-1].contact
    mu_p = scene.contact.friction * c.pressure[keep] / 1e6
    ax.plot(np.degrees(alpha[keep]), mu_p, "k--", lw=0.8, label="+-mu p, last step")
    ax.plot(np.degrees(alpha[keep]), -mu_p, "k--", lw=0.8)
    for state, marker in ((STICK, "o"), (SLIP, "x")):
        on = keep[c.status[keep] == state]
        ax.plot(np.degrees(alpha[on]), c.shear[on, 0] / 1e6, marker, ms=3, color="k", mfc="none",
                label=f"{STATE_NAMES[state]}, last step")
    ax.set_xlabel("angle from load direction (deg)")
    ax.set_ylabel("shear on the bore, along +theta (MPa)")
    ax.set_title("friction: shear at every step")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def pressure_grid(contact, values, symmetric: bool):
    """Nodal values of the pin surface as a grid (levels, angles), the angles and the levels
    z (m); a half model mirrored about its top level to the whole pin."""
    angles, levels = contact.pin_grid
    grid = values.reshape(levels.size, angles.size)
    if symmetric:
        levels = np.concatenate([levels, 2 * levels[-1] - levels[-2::-1]])
        grid = np.concatenate([grid, grid[-2::-1]])
    return grid, angles, levels


def pressure_pictures(folder: Path, run, scene, contact, symmetric: bool) -> None:
    """3D: the contact pressure of the last step on the pin's surface (pressure_map.png,
    pyvista off-screen), and its peak and resultant along the axis at every step
    (axial_profile.png); a half model (symmetric) shown whole."""
    pyvista = offscreen_pyvista()
    last = run.steps[-1]
    grid, angles, levels = pressure_grid(contact, last.contact.pressure, symmetric)
    theta = np.append(angles, angles[0] + 2 * np.pi)
    grid = np.concatenate([grid, grid[:, :1]], axis=1)
    t, z = np.meshgrid(theta, levels)
    r = scene.geometry.pin_radius
    surface = pyvista.StructuredGrid(r * np.cos(t), r * np.sin(t), z)
    surface["pressure (MPa)"] = grid.ravel(order="F") / 1e6
    plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 900))
    plotter.add_mesh(surface, scalars="pressure (MPa)", cmap="viridis", smooth_shading=True)
    d = np.asarray(scene.load.direction)
    middle = 0.5 * (levels[0] + levels[-1])
    distance = 1.8 * max(levels[-1] - levels[0], 4 * r)
    view = np.array([d[0], d[1], 0.35])   # from the loaded side, a little above
    eye = np.array([0, 0, middle]) + distance * view / np.linalg.norm(view)
    plotter.camera_position = [tuple(eye), (0, 0, middle), (0, 0, 1)]
    plotter.add_text(f"contact pressure on the pin, approach {last.approach * 1e6:.3g} um, "
                     f"tilt {scene.geometry.tilt_deg:g} deg", font_size=10)
    save_image(plotter.screenshot(return_img=True), folder / "pressure_map.png")
    plotter.close()

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
    ring = tributary_lengths(contact.pin_reference[:angles.size, :2])
    for i, step in enumerate(run.steps, start=1):
        p, _, z = pressure_grid(contact, step.contact.pressure, symmetric)
        along, _, _ = pressure_grid(contact, np.cos(step.contact.angle - np.arctan2(d[1], d[0])),
                                    symmetric)
        colour = plt.cm.plasma(i / (len(run.steps) + 1))
        ax.plot(z * 1e3, p.max(axis=1) / 1e6, color=colour, lw=1)
        bx.plot(z * 1e3, (p * along * ring).sum(axis=1) / 1e3, color=colour, lw=1)
    ax.set_xlabel("z (mm)")
    ax.set_ylabel("peak contact pressure (MPa)")
    ax.set_title("peak pressure along the pin, every step")
    bx.set_xlabel("z (mm)")
    bx.set_ylabel("line load along the load (kN/m)")
    bx.set_title("pressure resultant per unit length")
    for a in (ax, bx):
        a.grid(alpha=0.3)
    save_png(fig, folder / "axial_profile.png", layout=True)
