"""The FE scene (`kind = "fem"`): geometry, materials, contact, load, mesh, solver, output."""

import math
from typing import Literal

import pydantic

from laws.elastic import Joint
from meshes.model import Geometry, MeshOptions
from pinbore.scene import Strict


class Material(Strict):
    """Linear elastic, isotropic."""

    E: float = pydantic.Field(gt=0, description="Young's modulus (Pa)")
    nu: float = pydantic.Field(gt=-1, lt=0.5, description="Poisson's ratio")


class Materials(Strict):
    pin: Material
    bore: Material


class Contact(Strict):
    """Unilateral contact between the pin surface and the bore surface.

    penalty_factor scales the penalty stiffness E*/h (h: element size on the contact arc).
    gap_tolerance (m) is the largest penetration the augmented Lagrangian accepts.
    """

    method: Literal["penalty", "augmented-lagrangian"]
    friction: float = pydantic.Field(ge=0)
    penalty_factor: float | None = pydantic.Field(default=None, gt=0)
    gap_tolerance: float | None = pydantic.Field(default=None, gt=0)

    @pydantic.model_validator(mode="after")
    def _supported(self):
        if self.friction > 0:
            raise ValueError("friction > 0 is not supported yet (frictional contact is issue 3)")
        if self.gap_tolerance is not None and self.method != "augmented-lagrangian":
            raise ValueError("gap_tolerance applies to method = \"augmented-lagrangian\" only")
        return self


class Load(Strict):
    """The hub moves the clearance through free space, then pushes max_approach further, in
    equal steps, or in geometric steps from first_approach when that is given."""

    max_approach: float = pydantic.Field(gt=0, description="hub displacement beyond first touch (m)")
    steps: int = pydantic.Field(ge=1)
    direction_deg: float = pydantic.Field(ge=-360, le=360)
    first_approach: float | None = pydantic.Field(default=None, gt=0)

    @pydantic.model_validator(mode="after")
    def _steps(self):
        if self.first_approach is not None and (self.first_approach >= self.max_approach
                                                or self.steps < 2):
            raise ValueError("first_approach must be below max_approach, with steps >= 2")
        return self

    @property
    def approaches(self) -> list[float]:
        """The approach (m) of every load step."""
        if self.first_approach is None:
            return [self.max_approach * (k + 1) / self.steps for k in range(self.steps)]
        ratio = (self.max_approach / self.first_approach) ** (1 / (self.steps - 1))
        return [self.first_approach * ratio**k for k in range(self.steps)]

    @property
    def direction(self) -> tuple[float, float]:
        a = math.radians(self.direction_deg)
        return (math.cos(a), math.sin(a))


class Solver(Strict):
    newton_max_it: int = pydantic.Field(default=25, ge=1)
    max_cutbacks: int = pydantic.Field(default=5, ge=0)
    uzawa_max_it: int = pydantic.Field(default=25, ge=1)


class Output(Strict):
    fields: bool = False
    picture: bool = True


class FemScene(Strict):
    kind: Literal["fem"]
    geometry: Geometry
    materials: Materials
    contact: Contact
    load: Load
    mesh: MeshOptions = MeshOptions()
    solver: Solver = Solver()
    output: Output = Output()

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        wall = self.geometry.pin_radius - self.geometry.hub_radius
        if self.mesh.contact_size is not None and self.mesh.contact_size >= wall:
            raise ValueError("mesh.contact_size must be smaller than pin_radius - hub_radius")
        if self.load.max_approach >= self.geometry.pin_radius - self.geometry.hub_radius:
            raise ValueError("load.max_approach must be smaller than the pin wall (small strain)")
        return self

    @property
    def joint(self) -> Joint:
        """The joint of the contact laws (2D: per unit length; length = 1 m unless given)."""
        g, pin, bore = self.geometry, self.materials.pin, self.materials.bore
        return Joint(g.bore_radius, g.pin_radius, bore.E, bore.nu, pin.E, pin.nu, g.length or 1.0)

    @property
    def effective_modulus(self) -> float:
        """E* with 1/E* = (1-nu_pin^2)/E_pin + (1-nu_bore^2)/E_bore (Pa), plane strain."""
        return self.joint.e_star
