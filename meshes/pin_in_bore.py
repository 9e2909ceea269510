"""Gmsh models of a pin in a bore.

Geometry (2D, plane strain; 3D: the same section extruded along z over `length`, or over
half of it when the mid-plane is a plane of symmetry):

    housing: annulus  bore_radius  < r < housing_radius   (outer edge clamped)
    pin:     annulus  hub_radius   < r < pin_radius       (inner edge = rigid hub)

The two bodies do not touch: the clearance c = bore_radius - pin_radius separates them.
The mesh is built in a frame where the load points along -y, so that the contact arc is
centred on the angle -90 deg, and then rotated rigidly into the scene's load direction.
Rotating the finished mesh keeps scenes that differ only in load direction exact rotations
of each other.

In 3D the pin may run on beyond the bore's ends (pin_overhang: a pin through a lug, whose
bore edges then carry the edge loading). The layers close in towards the ends
(z_k = L/2 (1 - cos(pi k / n)) over the whole length: the half model has exactly the nodes
of the full one below the mid-plane), and a tilted pin is turned about the axis through its
middle normal to the load.

A worn joint (meshes.worn) is meshed as the round joint of its base circles, and its nodes
are then moved radially onto the worn surfaces, in the scene's frame.
"""

import math

import gmsh
import numpy as np

from pinbore.meshes.model import (BORE_SURFACE, DEFAULT_LAYERS, HOUSING, HOUSING_EDGE,
                                  HOUSING_ENDS, HUB, PIN, PIN_ENDS, PIN_SURFACE, SYMMETRY,
                                  MeshOptions, generate, overhang_layers, uses_symmetry)
from pinbore.meshes.sizing import Sizing, far_size, wall_size

CANONICAL_DIRECTION_DEG = -90.0


def size_field(geometry, sizing: Sizing):
    """Element size h(x, y): fine on the contact arc of each body's own surface (pin or
    bore), growing linearly with the distance from it."""
    centre = math.radians(CANONICAL_DIRECTION_DEG)
    middle = 0.5 * (geometry.pin_radius + geometry.bore_radius)
    far, wall = far_size(geometry, sizing), wall_size(geometry, sizing)

    def h(x, y):
        r = math.hypot(x, y)
        surface = geometry.pin_radius if r < middle else geometry.bore_radius
        offset = abs(math.remainder(math.atan2(y, x) - centre, 2 * math.pi))
        if offset <= sizing.arc_half_angle:
            distance = abs(r - surface)
        else:
            distance = min(math.hypot(x - surface * math.cos(centre + s * sizing.arc_half_angle),
                                      y - surface * math.sin(centre + s * sizing.arc_half_angle))
                           for s in (-1, 1))
        size = min(sizing.contact_size + sizing.grading * distance,
                   far + sizing.grading * abs(r - surface))
        return min(size, wall) if r < middle else size

    return h


def layer_heights(n: int, half: bool) -> list[float]:
    """Cumulative heights (fractions of the extrusion) of n layers closing in towards the
    ends: z_k = (1 - cos(pi k / N)) / 2 of the length, N = n (whole) or 2 n (half model)."""
    total = 2 * n if half else n
    z = [0.5 * (1 - math.cos(math.pi * k / total)) for k in range(1, n + 1)]
    return [v / z[-1] for v in z]


def build(geometry, sizing: Sizing, direction_deg: float, mesh: MeshOptions = MeshOptions(),
          worn=None) -> None:
    """Build and mesh the model in the current gmsh session (see `session`); a worn joint
    (meshes.worn.WornJoint): the round joint of its base circles, its nodes then moved onto
    the worn surfaces."""
    round_geometry = geometry
    if worn is not None:
        geometry = worn.base_geometry(geometry)
    gmsh.model.add("pin_in_bore")
    occ = gmsh.model.occ
    # The pin and bore circles are split at the ends of the refined arc, so that gmsh meshes
    # the fine arc as a curve of its own (on a whole circle it samples a narrow fine region
    # too coarsely and the arc comes out uniform).
    ends = (math.radians(CANONICAL_DIRECTION_DEG) - sizing.arc_half_angle,
            math.radians(CANONICAL_DIRECTION_DEG) + sizing.arc_half_angle)

    def split_circle(radius):
        """A closed loop of arcs (each < 180 deg, as OCC asks) through shared points that
        include the ends of the refined arc."""
        span = ends[1] - ends[0]
        rest = 2 * math.pi - span
        angles = ([ends[0] + span * i / math.ceil(span / 2.5) for i in range(math.ceil(span / 2.5))]
                  + [ends[1] + rest * i / math.ceil(rest / 2.5) for i in range(math.ceil(rest / 2.5))])
        centre = occ.addPoint(0, 0, 0)
        points = [occ.addPoint(radius * math.cos(a), radius * math.sin(a), 0) for a in angles]
        arcs = [occ.addCircleArc(p, centre, q) for p, q in zip(points, points[1:] + points[:1])]
        return occ.addCurveLoop(arcs)

    def circle(radius):
        return occ.addCurveLoop([occ.addCircle(0, 0, 0, radius)])

    pin = [(2, occ.addPlaneSurface([split_circle(geometry.pin_radius), circle(geometry.hub_radius)]))]
    housing = [(2, occ.addPlaneSurface([circle(geometry.housing_radius),
                                        split_circle(geometry.bore_radius)]))]
    half = uses_symmetry(geometry, mesh)
    if geometry.dim == 3:
        n = mesh.layers or DEFAULT_LAYERS
        height = geometry.length / 2 if half else geometry.length
        heights = layer_heights(n, half)
        pin_base = pin
        pin, housing = (occ.extrude(body, 0, 0, height, [1] * n, heights)
                        for body in (pin, housing))
        pin_top, pin, housing = [pin[0]], [pin[1]], [housing[1]]
        overhang = geometry.pin_overhang
        if overhang:   # the pin runs on beyond the bore's ends, in layers growing outwards
            m = overhang_layers(n)
            ends = [(pin_base, -overhang)] + ([] if half else [(pin_top, overhang)])
            pin += [occ.extrude(face, 0, 0, dz, [1] * m, layer_heights(m, True))[1]
                    for face, dz in ends]
    occ.synchronize()
    _tag_groups(geometry, pin, housing, half)

    h = size_field(geometry, sizing)
    gmsh.model.mesh.setSizeCallback(lambda dim, tag, x, y, z, lc: h(x, y))
    for option, value in (("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
                          ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.Algorithm", 6)):
        gmsh.option.setNumber(option, value)
    generate(gmsh, geometry.dim)
    if geometry.tilt_deg:
        _tilt_pin(pin, geometry)
    _rotate_mesh(math.radians(direction_deg - CANONICAL_DIRECTION_DEG))
    if worn is not None:
        _wear_nodes(pin, housing, round_geometry, worn)


def _tilt_pin(pin, geometry) -> None:
    """Turn the pin's mesh nodes by geometry.tilt_frame about (0, 0, length / 2)."""
    centre = np.array([0.0, 0.0, geometry.length / 2])
    done = set()
    for _, volume in pin:
        tags, coords, _ = gmsh.model.mesh.getNodes(3, volume, includeBoundary=True)
        for tag, x in zip(tags, coords.reshape(-1, 3)):
            if tag not in done:
                done.add(tag)
                gmsh.model.mesh.setNode(int(tag), list((x - centre) @ geometry.tilt_frame.T + centre), [])


def _wear_nodes(pin, housing, geometry, worn) -> None:
    """Move the nodes of the round joint of the base circles radially onto the worn surfaces,
    the move tapered linearly to nothing at the hub and at the housing's edge (meshes.worn)."""
    pin_wall = worn.pin_base - geometry.hub_radius
    housing_wall = geometry.housing_radius - worn.bore_base
    for bodies, excess, weight in (
            (pin, worn.pin_excess, lambda r: (r - geometry.hub_radius) / pin_wall),
            (housing, worn.bore_excess, lambda r: (geometry.housing_radius - r) / housing_wall)):
        tags, coords = [], []
        for _, surface in bodies:
            t, x, _ = gmsh.model.mesh.getNodes(2, surface, includeBoundary=True)
            tags.append(t)
            coords.append(x.reshape(-1, 3))
        tags, first = np.unique(np.concatenate(tags), return_index=True)
        x = np.concatenate(coords)[first]
        r, theta = np.hypot(x[:, 0], x[:, 1]), np.arctan2(x[:, 1], x[:, 0])
        scale = 1 + excess(theta)[0] * np.clip(weight(r), 0.0, 1.0) / r
        for tag, point, k in zip(tags, x, scale):
            gmsh.model.mesh.setNode(int(tag), [point[0] * k, point[1] * k, point[2]], [])


def _tag_groups(geometry, pin, housing, half: bool) -> None:
    """Physical groups: the two bodies and their named boundaries, found by their radius."""
    dim = geometry.dim
    gmsh.model.addPhysicalGroup(dim, [t for _, t in pin], PIN, "pin")
    gmsh.model.addPhysicalGroup(dim, [t for _, t in housing], HOUSING, "housing")
    by_radius = {HUB: geometry.hub_radius, PIN_SURFACE: geometry.pin_radius,
                 BORE_SURFACE: geometry.bore_radius, HOUSING_EDGE: geometry.housing_radius}
    groups = {tag: [] for tag in by_radius} | {PIN_ENDS: [], HOUSING_ENDS: [], SYMMETRY: []}
    faces = {t for body in (pin, housing)
             for _, t in gmsh.model.getBoundary(body, combined=True, oriented=False)}
    for tag in sorted(faces):
        if dim == 3 and gmsh.model.getType(2, tag) == "Plane":
            box = gmsh.model.getBoundingBox(2, tag)
            split = 0.5 * (geometry.bore_radius + geometry.housing_radius)
            if half and box[2] > 0.25 * geometry.length:
                groups[SYMMETRY].append(tag)
            else:
                groups[PIN_ENDS if box[3] < split else HOUSING_ENDS].append(tag)
            continue
        radius = math.hypot(*_point_on(dim - 1, tag)[:2])
        groups[min(by_radius, key=lambda g: abs(by_radius[g] - radius))].append(tag)
    names = {HUB: "hub", PIN_SURFACE: "pin_surface", BORE_SURFACE: "bore_surface",
             HOUSING_EDGE: "housing_edge", PIN_ENDS: "pin_ends", HOUSING_ENDS: "housing_ends",
             SYMMETRY: "symmetry"}
    for group, tags in groups.items():
        if tags:
            gmsh.model.addPhysicalGroup(dim - 1, tags, group, names[group])


def _point_on(dim: int, tag: int) -> np.ndarray:
    """A point of the entity, at the middle of its parameter range (exact, unlike a bbox)."""
    low, high = gmsh.model.getParametrizationBounds(dim, tag)
    return gmsh.model.getValue(dim, tag, 0.5 * (np.asarray(low) + np.asarray(high)))


def _rotate_mesh(angle: float) -> None:
    """Rotate every mesh node about the z axis by `angle` (rad)."""
    c, s = math.cos(angle), math.sin(angle)
    gmsh.model.mesh.affineTransform([c, -s, 0, 0, s, c, 0, 0, 0, 0, 1, 0])
