"""The FE scene (`kind = "fem"`): geometry, materials, contact, load, mesh, solver, output."""

import functools
import math
from typing import Literal

import pydantic

from pinbore.core.scene import Strict
from pinbore.laws.elastic import Joint
from pinbore.meshes.model import Geometry, MeshOptions
from pinbore.meshes.sizing import Sizing, check_cells, estimate_sizing


class Material(Strict):
    """Linear elastic, isotropic."""

    E: float = pydantic.Field(gt=0, description="Young's modulus (Pa)")
    nu: float = pydantic.Field(gt=-1, lt=0.5, description="Poisson's ratio")


class Materials(Strict):
    pin: Material
    bore: Material


class Contact(Strict):
    """Unilateral contact between the pin surface and the bore surface, with Coulomb
    friction of coefficient `friction` (fem.contact explains the scheme).

    penalty_factor scales the penalty stiffness E*/h (h: element size on the contact arc).
    gap_tolerance (m) is the largest penetration, and the largest slip of a stuck node over a
    step, that the augmented Lagrangian accepts.
    """

    method: Literal["penalty", "augmented-lagrangian"]
    friction: float = pydantic.Field(ge=0, description="Coulomb coefficient mu (0: frictionless)")
    penalty_factor: float | None = pydantic.Field(default=None, gt=0)
    gap_tolerance: float | None = pydantic.Field(default=None, gt=0)

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.gap_tolerance is not None and self.method != "augmented-lagrangian":
            raise ValueError("gap_tolerance applies to method = \"augmented-lagrangian\" only")
        return self


class Load(Strict):
    """The hub moves the clearance through free space, then pushes max_approach further, in
    equal steps, or in geometric steps from first_approach when that is given.

    Then, optionally, with the approach held, the hub turns the pin about its axis by
    rotation_deg, or pushes it across the load direction by tangential_push (m, towards
    +90 deg from the load), in slide_steps equal steps: the pin sticks, then slips.
    Rotations are small-strain (linearised): R phi^2 / 2 must stay below 1 % of the approach.
    """

    max_approach: float = pydantic.Field(ge=0, description="hub displacement beyond first touch (m)")
    steps: int = pydantic.Field(ge=1, le=10_000)
    direction_deg: float = pydantic.Field(ge=-360, le=360)
    first_approach: float | None = pydantic.Field(default=None, gt=0)
    rotation_deg: float | None = None
    tangential_push: float | None = None
    slide_steps: int = pydantic.Field(default=10, ge=1, le=10_000)

    @pydantic.model_validator(mode="after")
    def _steps(self):
        slide = "rotation_deg" if self.rotation_deg is not None else (
            "tangential_push" if self.tangential_push is not None else None)
        if self.max_approach <= 0:
            raise ValueError("max_approach must be > 0 (m)"
                             + (f": {slide} needs a radial push first" if slide else ""))
        if self.rotation_deg is not None and self.tangential_push is not None:
            raise ValueError("give rotation_deg or tangential_push, not both")
        if self.rotation_deg == 0 or self.tangential_push == 0:
            raise ValueError(f"{slide} must not be 0 (leave it out for a push only)")
        if self.first_approach is not None and (self.first_approach >= self.max_approach
                                                or self.steps < 2):
            raise ValueError("first_approach must be below max_approach, with steps >= 2")
        return self

    @property
    def approaches(self) -> list[float]:
        """The approach (m) of every load step of the radial push."""
        if self.first_approach is None:
            return [self.max_approach * (k + 1) / self.steps for k in range(self.steps)]
        ratio = (self.max_approach / self.first_approach) ** (1 / (self.steps - 1))
        return [self.first_approach * ratio**k for k in range(self.steps)]

    @property
    def programme(self) -> list[tuple[float, float, float]]:
        """Every load step as (approach (m), rotation (rad), tangential push (m))."""
        points = [(a, 0.0, 0.0) for a in self.approaches]
        rotation = math.radians(self.rotation_deg or 0.0)
        push = self.tangential_push or 0.0
        if rotation or push:
            n = self.slide_steps
            points += [(self.max_approach, rotation * k / n, push * k / n) for k in range(1, n + 1)]
        return points

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
        if self.geometry.dim == 2:
            for key in ("layers", "symmetry"):
                if getattr(self.mesh, key) is not None:
                    raise ValueError(f"mesh.{key} applies to dim = 3 only")
        wall = self.geometry.pin_radius - self.geometry.hub_radius
        if self.mesh.contact_size is not None and self.mesh.contact_size >= wall:
            raise ValueError("mesh.contact_size must be smaller than pin_radius - hub_radius")
        if self.load.max_approach >= self.geometry.pin_radius - self.geometry.hub_radius:
            raise ValueError("load.max_approach must be smaller than the pin wall (small strain)")
        if self.mesh.symmetry and self.geometry.tilt_deg:
            raise ValueError("mesh.symmetry: a tilted pin is not symmetric about the mid-plane")
        check_cells(self.geometry, self.sizing, self.mesh)
        if self.load.rotation_deg is not None:
            phi = math.radians(self.load.rotation_deg)
            if self.geometry.pin_radius * phi**2 / 2 > 0.01 * self.load.max_approach:
                limit = math.degrees(math.sqrt(0.02 * self.load.max_approach / self.geometry.pin_radius))
                raise ValueError(f"load.rotation_deg: |rotation| must be <= {limit:.3g} deg here "
                                 "(small-strain rotation: R phi^2/2 <= 1 % of max_approach)")
        return self

    @property
    def joint(self) -> Joint:
        """The joint of the contact laws (2D: per unit length; length = 1 m unless given)."""
        g, pin, bore = self.geometry, self.materials.pin, self.materials.bore
        return Joint(g.bore_radius, g.pin_radius, bore.E, bore.nu, pin.E, pin.nu, g.length or 1.0)

    @functools.cached_property
    def sizing(self) -> Sizing:
        """Where the mesh is refined and how finely (meshes.sizing), for this scene's joint and load."""
        return estimate_sizing(self.joint, self.load.max_approach, self.mesh.contact_size,
                               self.mesh.grading, self.mesh.refine)

    @property
    def effective_modulus(self) -> float:
        """E* with 1/E* = (1-nu_pin^2)/E_pin + (1-nu_bore^2)/E_bore (Pa), plane strain."""
        return self.joint.e_star
