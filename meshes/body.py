r"""Gmsh models of the flexible bodies of a mechanism: a link (a bar with a bore eye at each
end, or with plain end faces) and a panel (a plate with hinge knuckles along one edge).

Frames (m), the same as the body's before its centre of mass is taken as origin:

    bar:   x along the bar, from the interface "a" at x = 0 to "b" at x = length;
           y across it (width), z through it (thickness); the section centred on y = z = 0.
           With eye_radius, each end is rounded (radius width / 2) about a bore of that
           radius through the thickness: the interface is the bore's surface, its frame at
           the bore's centre. Without, the interface is the end face, its frame at the
           face's centre. dim = 2: the rectangle (and disks) of the x-y plane (plane stress,
           the thickness out of plane); dim = 3: the solid.
    panel: a plate 0 <= x <= length (the span away from the hinge line), 0 <= y <= width (along
           the hinge line), |z| <= thickness / 2; with `lugs`, one knuckle a lug at each
           position y_k: a tube of outer radius lug_radius about the hinge axis (along y,
           through x = -lug_radius, z = 0), lug_width long, joined to the plate's edge by a
           web, around a bore of radius lug_bore_radius (the interface "lug<k>", its frame at
           the bore's centre). Without lugs, the edge face x = 0 is the interface "edge".

The mesh carries one physical group, the body's cells. An interface's facets are found on
the mesh by its geometry (`interface_at`), so a bore is exactly the surface the geometry
says, whatever the boolean operations made of Gmsh's entities.
"""

import math
from typing import Literal

import numpy as np
import pydantic

from pinbore.core.scene import Strict
from pinbore.meshes.model import MAX_CELLS, generate

BODY = 1                      # the physical group of the body's cells
SURFACE_TOLERANCE = 1e-6      # of the body's size: a facet on an interface's surface
BORE_CELLS = 10               # a bore's radius is at least cell_size / BORE_CELLS


class BodyGeometry(Strict):
    """A flexible body's shape and mesh size (m). See the module's docstring for the frames."""

    shape: Literal["bar", "panel"]
    dim: Literal[2, 3]
    length: float = pydantic.Field(gt=0)
    width: float = pydantic.Field(gt=0)
    thickness: float = pydantic.Field(gt=0)
    cell_size: float = pydantic.Field(gt=0, description="the largest element edge (m)")
    eye_radius: float | None = pydantic.Field(default=None, gt=0)
    lugs: list[float] = pydantic.Field(default_factory=list)
    lug_radius: float | None = pydantic.Field(default=None, gt=0)
    lug_bore_radius: float | None = pydantic.Field(default=None, gt=0)
    lug_width: float | None = pydantic.Field(default=None, gt=0)
    max_cells: int | None = pydantic.Field(default=None, ge=1, description=(
        "the most cells the mesh may have, estimated before meshing (default: MAX_CELLS, "
        "2.5e5 in 2D, 1.5e5 in 3D)"))

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        lug_keys = {"lugs": self.lugs or None, "lug_radius": self.lug_radius,
                    "lug_bore_radius": self.lug_bore_radius, "lug_width": self.lug_width}
        if self.shape == "bar":
            for key, value in lug_keys.items():
                if value is not None:
                    raise ValueError(f"{key} belongs to a panel (shape = \"panel\"), not a bar")
            if self.eye_radius is not None and self.eye_radius >= self.width / 2:
                raise ValueError("eye_radius must be smaller than width / 2 (the eye's wall)")
        else:
            if self.dim != 3:
                raise ValueError("a panel is a 3D solid: dim = 3")
            if self.eye_radius is not None:
                raise ValueError("eye_radius belongs to a bar; a panel's bores are lug_bore_radius")
            if self.lugs:
                missing = [k for k, v in lug_keys.items() if v is None]
                if missing:
                    raise ValueError(f"lugs need {', '.join(missing)}")
                if self.lug_bore_radius >= self.lug_radius:
                    raise ValueError("lug_bore_radius must be smaller than lug_radius")
                if self.lug_radius <= self.thickness / 2:
                    raise ValueError("lug_radius must exceed thickness / 2 (the knuckle "
                                     "holds the plate's edge)")
                half = self.lug_width / 2
                ends = sorted((y - half, y + half) for y in self.lugs)
                if ends[0][0] < 0 or ends[-1][1] > self.width:
                    raise ValueError("each lug (y +- lug_width / 2) must lie on the edge "
                                     "0 <= y <= width")
                if any(b[0] <= a[1] for a, b in zip(ends, ends[1:])):
                    raise ValueError("the lugs overlap: space them by more than lug_width")
        if self.cell_size > min(self.length, self.width) / 2:
            raise ValueError("cell_size must be at most half the body's length and width")
        for key in ("eye_radius", "lug_bore_radius"):
            bore = getattr(self, key)
            if bore is not None and bore < self.cell_size / BORE_CELLS:
                raise ValueError(f"{key} {bore:g} m is less than cell_size / {BORE_CELLS:g} "
                                 f"({self.cell_size / BORE_CELLS:g} m): cells that large cannot "
                                 "mesh the bore the interface is tied to")
        limit = self.max_cells or MAX_CELLS[self.dim]
        if self.estimated_cells > limit:
            raise ValueError(f"the mesh would have about {self.estimated_cells:.3g} cells, more than "
                             f"{limit:.3g} (a larger cell_size; or max_cells, if the machine can take it)")
        return self

    @property
    def estimated_cells(self) -> float:
        """The cells of the body's mesh, estimated before meshing: its plate's area (2D) or
        volume (3D) over that of a regular triangle of edge cell_size h (sqrt(3)/4 h^2), or of
        a regular tetrahedron flattened to the thickness t where t < h (h^2 min(h, t) /
        (6 sqrt(2))). The shipped bodies mesh to 0.9-2.6 times it."""
        h = self.cell_size
        if self.dim == 2:
            return self.length * self.width / (math.sqrt(3) / 4 * h * h)
        return self.length * self.width * self.thickness / (h * h * min(h, self.thickness) / (6 * math.sqrt(2)))

    @property
    def interfaces(self) -> dict[str, tuple[float, float, float]]:
        """Each interface's name and the centre of its frame (mesh frame, m)."""
        if self.shape == "bar":
            return {"a": (0.0, 0.0, 0.0), "b": (self.length, 0.0, 0.0)}
        if not self.lugs:
            return {"edge": (0.0, self.width / 2, 0.0)}
        return {f"lug{k + 1}": (-self.lug_radius, y, 0.0) for k, y in enumerate(self.lugs)}

    @property
    def size(self) -> float:
        """The body's largest extent (m)."""
        return max(self.length, self.width, self.thickness)

    def interface_at(self, name: str, x: np.ndarray) -> np.ndarray:
        """Whether the points x (dim, n) lie on the surface of interface `name` (DOLFINx's
        marker convention: one row per coordinate)."""
        t = SURFACE_TOLERANCE * self.size
        x = np.asarray(x)
        if self.shape == "bar":
            c = 0.0 if name == "a" else self.length
            if self.eye_radius is None:
                return np.abs(x[0] - c) <= t
            return np.abs(np.hypot(x[0] - c, x[1]) - self.eye_radius) <= t
        if name == "edge":
            return np.abs(x[0]) <= t
        y = self.lugs[int(name.removeprefix("lug")) - 1]
        return ((np.abs(np.hypot(x[0] + self.lug_radius, x[2]) - self.lug_bore_radius) <= t)
                & (np.abs(x[1] - y) <= self.lug_width / 2 + t))


def build(gmsh, body: BodyGeometry) -> None:
    """Build and mesh the body in the current gmsh model (first-order cells; the FE space's
    degree is the solver's): one physical group BODY of its cells."""
    occ = gmsh.model.occ
    if body.shape == "bar":
        tags = _bar(occ, body)
    else:
        tags = _panel(occ, body)
    occ.synchronize()
    gmsh.model.addPhysicalGroup(body.dim, tags, BODY, name="body")
    gmsh.option.setNumber("Mesh.MeshSizeMax", body.cell_size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 24)   # elements per 2 pi on a bore
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)   # HXT: parallel, fast on thin plates
    generate(gmsh, body.dim)


def _bar(occ, body: BodyGeometry) -> list[int]:
    L, w, t = body.length, body.width, body.thickness
    if body.dim == 2:
        shape = [(2, occ.addRectangle(0.0, -w / 2, 0.0, L, w))]
        if body.eye_radius is not None:
            ends = [(2, occ.addDisk(c, 0.0, 0.0, w / 2, w / 2)) for c in (0.0, L)]
            shape, _ = occ.fuse(shape, ends)
            holes = [(2, occ.addDisk(c, 0.0, 0.0, body.eye_radius, body.eye_radius)) for c in (0.0, L)]
            shape, _ = occ.cut(shape, holes)
        return [tag for _, tag in shape]
    shape = [(3, occ.addBox(0.0, -w / 2, -t / 2, L, w, t))]
    if body.eye_radius is not None:
        ends = [(3, occ.addCylinder(c, 0.0, -t / 2, 0.0, 0.0, t, w / 2)) for c in (0.0, L)]
        shape, _ = occ.fuse(shape, ends)
        holes = [(3, occ.addCylinder(c, 0.0, -t / 2, 0.0, 0.0, t, body.eye_radius)) for c in (0.0, L)]
        shape, _ = occ.cut(shape, holes)
    return [tag for _, tag in shape]


def _panel(occ, body: BodyGeometry) -> list[int]:
    a, b, h = body.length, body.width, body.thickness
    shape = [(3, occ.addBox(0.0, 0.0, -h / 2, a, b, h))]
    if not body.lugs:
        return [tag for _, tag in shape]
    R, w = body.lug_radius, body.lug_width
    knuckles = []
    for y in body.lugs:
        knuckles.append((3, occ.addCylinder(-R, y - w / 2, 0.0, 0.0, w, 0.0, R)))
        knuckles.append((3, occ.addBox(-R, y - w / 2, -h / 2, R, w, h)))
    shape, _ = occ.fuse(shape, knuckles)
    bores = [(3, occ.addCylinder(-R, y - w / 2, 0.0, 0.0, w, 0.0, body.lug_bore_radius))
             for y in body.lugs]
    shape, _ = occ.cut(shape, bores)
    return [tag for _, tag in shape]
