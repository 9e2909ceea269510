"""From a scene to the DOLFINx objects: mesh, elasticity, contact, load stepper."""

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import math

import dolfinx.io.gmsh
import numpy as np
from mpi4py import MPI

from pinbore.fem.contact import PinBoreContact
from pinbore.fem.elasticity import Elasticity
from pinbore.fem.plasticity import ElastoPlastic
from pinbore.fem.scene import FemScene
from pinbore.fem.solver import LoadStepper
from pinbore.meshes import pin_in_bore
from pinbore.meshes.model import gmsh_session
from pinbore.meshes.sizing import half_angle_at, law_forces

DEFAULT_PENALTY_FACTOR = 100.0   # eps = factor E*/h
DEFAULT_GAP_TOLERANCE = 1e-4  # fraction of max_approach


def mesh_of(scene: FemScene, comm=MPI.COMM_WORLD, worn=None):
    """Build the gmsh model on rank 0 and distribute it: (MeshData, Sizing). `worn`: the
    scene's worn joint (worn_joint), when its geometry names a wear_file."""
    if (scene.geometry.wear_file is None) != (worn is None):
        raise ValueError("a scene naming a wear_file is meshed with its worn joint "
                         "(fem.scene.worn_joint), and only such a scene")
    sizing = scene.sizing_of(worn)
    with gmsh_session():
        if comm.rank == 0:
            pin_in_bore.build(scene.geometry, sizing, scene.load.direction_deg, scene.mesh_options,
                              worn)
        data = dolfinx.io.gmsh.model_to_mesh(pin_in_bore.gmsh.model, comm, 0, gdim=scene.geometry.dim)
    return data, sizing


def penalty_of(scene: FemScene, contact_size: float) -> float:
    """Penalty stiffness eps = factor * E* / h (Pa/m), h the element size on the contact arc."""
    factor = scene.contact.penalty_factor or DEFAULT_PENALTY_FACTOR
    return factor * scene.effective_modulus / contact_size


def residual_tolerance(scene: FemScene, penalty_per_node: float) -> float:
    """Newton's absolute tolerance on the nodal forces (N/m).

    A billionth of the force scale E* max_approach, but above the round-off floor of the
    contact forces: a gap carries round-off of eps_machine R (node coordinates of size R),
    which the penalty turns into forces of eps * h * eps_machine * R per node. Below that
    floor Newton cannot go (measured: a coarse mesh stalled at 1e-4 N/m, cut back to nothing).
    """
    floor = 1e3 * np.finfo(float).eps * penalty_per_node * scene.geometry.bore_radius
    return max(1e-9 * scene.effective_modulus * scene.load.max_approach, floor)


def tilt_frame(scene: FemScene) -> np.ndarray:
    """The pin's tilt (geometry.tilt_frame) in the scene's frame, the load along its direction."""
    a = np.radians(scene.load.direction_deg - pin_in_bore.CANONICAL_DIRECTION_DEG)
    turn = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    return turn @ scene.geometry.tilt_frame @ turn.T


def first_touch(pin_X: np.ndarray, direction, geometry, worn=None) -> float:
    """Hub travel (m) along `direction` at which the first pin node meets the bore: the
    clearance, or less for a tilted pin (its end reaches out); a worn joint's, where its
    worn pin first meets its worn bore (meshes.worn.WornJoint.touch)."""
    if worn is not None:
        return worn.touch(math.degrees(math.atan2(direction[1], direction[0])))[0]
    if not geometry.tilt_deg:
        return geometry.clearance
    along = pin_X[:, :2] @ np.asarray(direction)[:2]
    radius = geometry.bore_radius_at(pin_X[:, 2])
    return float(np.min(-along + np.sqrt(along**2 - np.sum(pin_X[:, :2]**2, axis=1) + radius**2)))


def overlap_shift(half_angle: float, pin_radius: float, clearance: float) -> float:
    """Hub travel beyond touch (m) at which a rigid pin, moved along the load direction,
    overlaps its bore over +-half_angle (rad). The pin's centre at s = c + a from the bore's
    puts its surface point at angle phi on the bore circle when
    s^2 + 2 R_p cos(phi) s - c (2 R_p + c) = 0  (R_b = R_p + c); for c << R, a = c (1/cos phi - 1)."""
    r, c = pin_radius, clearance
    b = r * math.cos(half_angle)
    return -b + math.sqrt(b * b + c * (2 * r + c)) - c


def first_shift(scene: FemScene, worn=None):
    """The rigid shift of the pin that starts the first push (fem.solver.LoadStepper): for a
    push d, the travel at which the rigid overlap spans the contact arc estimated for d,
    Persson's half-angle at the geometric mean of the two forces that bracket the FE's
    (meshes.sizing.law_forces; Liu's alone where Johnson's has none). None (the whole push)
    for a tilted pin, whose contact starts at an end.

    Moving the pin rigidly by all of d overlaps an arc far wider than the contact's (steel,
    c = 10 um, d = 2 um: 37 deg against 21 deg), and Newton spends its first iterations
    releasing nodes, each a new factorisation in 3D. Measured on the shipped scenes: the first
    step's Newton iterations 7-10 -> 2-6 in 2D; 3D (88k dofs) 8 -> 4. A worn joint: the round
    joint that conforms as it does where they first touch (meshes.worn.WornJoint.local_joint)."""
    if scene.geometry.dim == 3 and scene.geometry.tilt_deg:
        return None
    joint = (scene.joint if worn is None
             else worn.local_joint(scene.joint, scene.load.direction_deg)[0])

    def shift(d: float) -> float:
        liu_force, johnson_force = law_forces(d, joint)
        force = math.sqrt(liu_force * (liu_force if math.isnan(johnson_force) else johnson_force))
        return min(d, overlap_shift(half_angle_at(force, joint), joint.r_pin, joint.clearance))
    return shift


def bodies(scene: FemScene, comm=MPI.COMM_WORLD, worn=None):
    """The mesh, the bodies and their contact, without a solver: (elasticity, contact,
    material (None: the elasticity's constant stiffness alone), sizing, mesh data). `worn`:
    the scene's worn joint (fem.scene.worn_joint), when its geometry names a wear_file."""
    data, sizing = mesh_of(scene, comm, worn)
    el = Elasticity(data.mesh, data.cell_tags, data.facet_tags, scene.materials.pin,
                    scene.materials.bore,
                    (scene.tilt_pivot, scene.tilt_axis) if scene.geometry.dim == 3 else None)
    owned = el.V.dofmap.index_map.size_local
    surface = [d[d < owned] for d in (el.dofs["pin_surface"], el.dofs["bore_surface"])]
    g = scene.geometry
    options = {} if g.dim == 2 else {
        "relief": g.relief,
        "bore_end": g.length, "pin_frame": tilt_frame(scene), "pivot": g.length / 2,
        "pin_runs_on": g.pin_overhang > 0}
    if worn is not None:
        options["bore_wear"] = worn.bore_excess
    contact = PinBoreContact(el.V, *surface, g.bore_radius if worn is None else worn.bore_base,
                             penalty_of(scene, sizing.contact_size), el.K.createVecRight(),
                             friction=scene.contact.friction, **options)
    material = (ElastoPlastic(el, data.cell_tags, scene.materials.pin, scene.materials.bore)
                if scene.materials.plastic else None)
    return el, contact, material, sizing, data


def gap_tolerance(scene: FemScene) -> float:
    """The augmented Lagrangian's penetration tolerance (m)."""
    return scene.contact.gap_tolerance or DEFAULT_GAP_TOLERANCE * scene.load.max_approach


def build(scene: FemScene, comm=MPI.COMM_WORLD, worn=None):
    """Everything needed to solve the scene: (stepper, elasticity, contact, sizing, mesh data).
    `worn`: the scene's worn joint (fem.scene.worn_joint), when its geometry names a wear_file."""
    el, contact, material, sizing, data = bodies(scene, comm, worn)
    g = scene.geometry
    direction = np.append(scene.load.direction, [0.0] * (g.dim - 2))
    stepper = LoadStepper(el, contact, clearance=first_touch(contact.pin_X, direction, g, worn),
                          direction=direction, method=scene.contact.method,
                          gap_tolerance=gap_tolerance(scene),
                          newton_max_it=scene.solver.newton_max_it,
                          uzawa_max_it=scene.solver.uzawa_max_it,
                          max_cutbacks=scene.solver.max_cutbacks,
                          force_atol=residual_tolerance(scene, contact.penalty * sizing.contact_size),
                          couplings=contact.couplings(direction, sizing.arc_half_angle),
                          material=material, first_shift=first_shift(scene, worn))
    return stepper, el, contact, sizing, data
