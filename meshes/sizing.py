"""Where to refine: the expected contact arc and the element size on it.

pinbore grades the mesh so that it is fine on the contact arc and coarse elsewhere. The arc
is not known before solving, so it is estimated from the scene, generously, and used only to
place elements (never in a result):

1. force per length at an approach d: the larger of Liu et al.'s law (good for small
   clearance; it underestimates the FE force several times at c/R = 0.1) and Johnson's line
   contact (good for large clearance; no solution for small clearance);
2. contact half-angle from the Persson conformal solution at that force;
3. the refined arc covers 1.5 eps + 5 deg at the largest approach; the element size resolves
   the contact half-width at a tenth of the largest approach with 20 elements, and is never
   coarser than 0.5 deg of arc.
"""

import math
import warnings
from dataclasses import dataclass

import numpy as np

from pinbore.laws.elastic import Joint, johnson, liu, persson_half_angle
from pinbore.meshes.model import (DEFAULT_LAYERS, MAX_CELLS, Geometry, MeshOptions,
                                  overhang_layers, uses_symmetry)


@dataclass(frozen=True)
class Sizing:
    """Element size on the arc (m), the arc's half-angle (rad), the growth rate away from it,
    and a factor on every size (1/2^refine)."""

    contact_size: float
    arc_half_angle: float
    grading: float
    scale: float = 1.0


def law_forces(d: float, joint: Joint) -> tuple[float, float]:
    """Forces per length (N/m) at the approach d (m) by Liu's law and by Johnson's line
    contact (nan where Johnson's has no solution). They bracket the FE force: Liu's is low in
    a Hertzian contact (several times at c/R = 0.1), Johnson's is high in a conforming one
    (steel, c = 10 um, d = 2 um: Liu 1.05e5, Johnson 2.31e5, the FE 1.35e5 N/m)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Johnson out of its range
        return float(liu(d, joint)), float(johnson(d, joint))


def half_angle_at(force: float, joint: Joint) -> float:
    """Persson's contact half-angle (rad) at the force per length `force` (N/m)."""
    return persson_half_angle(force / (joint.e_star * joint.clearance))


def estimate_sizing(joint: Joint, max_approach, contact_size=None, grading=0.25, refine=0):
    """Sizing for `joint` pushed `max_approach` (m) beyond first touch."""
    def half_angle(d):
        return half_angle_at(np.nanmax(law_forces(d, joint)), joint)  # generously

    if contact_size is None:
        contact_size = joint.r_bore * min(math.sin(half_angle(0.1 * max_approach)) / 20,
                                          math.radians(0.5))
    arc = min(math.radians(95),
              1.5 * half_angle(max_approach) + math.radians(5) + 4 * contact_size / joint.r_bore)
    scale = 0.5**refine
    return Sizing(contact_size * scale, arc, grading * scale, scale)


def far_size(geometry: Geometry, sizing: Sizing) -> float:
    """Element size on the pin and bore circles away from the refined arc (m): 7.5 deg."""
    return sizing.scale * 0.5 * (geometry.pin_radius + geometry.bore_radius) * math.pi / 24


def wall_size(geometry: Geometry, sizing: Sizing) -> float:
    """Largest element size in the pin's wall between hub and surface (m): a third of it."""
    return sizing.scale * (geometry.pin_radius - geometry.hub_radius) / 3


TRIANGLES_PER_UNIT = 3.0   # Gmsh's triangles per h^2 of area (measured on the shipped scenes)


def expected_cells(geometry: Geometry, sizing: Sizing, mesh: MeshOptions) -> float:
    """About how many cells (triangles in 2D, tetrahedra in 3D) the mesh will have.

    Triangles: TRIANGLES_PER_UNIT * int dA / h^2 over the section with the size field of
    meshes.pin_in_bore.size_field: the bands beside the refined arc, where h = h0 + g d grows
    with the distance d from it (int_0^D dd / (h0 + g d)^2 = D / (h0 (h0 + g D)) per unit of
    arc length), and the rest at the far size growing the same way. 3D: every triangle
    extruded through the layers (and those of a pin running on beyond the bore) into three
    tetrahedra. Within 25 % of Gmsh on the shipped scenes; used to refuse a mesh that cannot
    be solved before building it, never in a result.
    """
    h0, g = sizing.contact_size, sizing.grading
    arc = 2 * sizing.arc_half_angle

    def band(radius, depth):
        return arc * radius * depth / (h0 * (h0 + g * depth))

    far = far_size(geometry, sizing)
    r_pin = np.linspace(geometry.hub_radius, geometry.pin_radius, 400)
    r_housing = np.geomspace(geometry.bore_radius, geometry.housing_radius, 400)
    h_pin = np.minimum(far + g * (geometry.pin_radius - r_pin), wall_size(geometry, sizing))
    h_housing = far + g * (r_housing - geometry.bore_radius)
    rest = (1 - arc / (2 * math.pi)) * (np.trapezoid(2 * math.pi * r_pin / h_pin**2, r_pin)
                                        + np.trapezoid(2 * math.pi * r_housing / h_housing**2,
                                                       r_housing))
    triangles = TRIANGLES_PER_UNIT * (band(geometry.pin_radius, geometry.pin_radius - geometry.hub_radius)
                                      + band(geometry.bore_radius,
                                             geometry.housing_radius - geometry.bore_radius)
                                      + rest)
    if geometry.dim == 2:
        return float(triangles)
    layers = mesh.layers or DEFAULT_LAYERS
    if geometry.pin_overhang:
        layers += overhang_layers(layers) * (1 if uses_symmetry(geometry, mesh) else 2)
    return float(3 * layers * triangles)


def check_cells(geometry: Geometry, sizing: Sizing, mesh: MeshOptions) -> None:
    """ValueError naming the rule if the mesh would exceed mesh.max_cells (or MAX_CELLS)."""
    cells = expected_cells(geometry, sizing, mesh)
    limit = mesh.max_cells or MAX_CELLS[geometry.dim]
    if cells > limit:
        raise ValueError(f"mesh: about {cells:.2g} cells expected (element size "
                         f"{sizing.contact_size:.2g} m on the contact arc), more than the limit "
                         f"{limit:.2g}; choose a larger mesh.contact_size (or a larger "
                         "load.max_approach), or raise mesh.max_cells")
