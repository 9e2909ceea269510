"""The FE scene (`kind = "fem"`): geometry, materials, contact, load, mesh, solver, output."""

import functools
import math
from dataclasses import dataclass
from typing import Annotated, Literal

import pydantic

from pinbore.core.errors import InputError
from pinbore.core.scene import Strict, named_file
from pinbore.laws.elastic import Joint
from pinbore.meshes.model import Geometry, MeshOptions
from pinbore.meshes.sizing import Sizing, check_cells, estimate_sizing
from pinbore.meshes.worn import read as read_worn


class Material(Strict):
    """Isotropic, linear elastic; with a yield stress, elasto-plastic (von Mises, isotropic
    hardening: linear with hardening_modulus H (0: perfectly plastic, the default), or the
    table `hardening` of (equivalent plastic strain, yield stress (Pa)) pairs from
    (0, yield_stress), held constant beyond its last pair; fem.plasticity)."""

    E: float = pydantic.Field(gt=0, description="Young's modulus (Pa)")
    nu: float = pydantic.Field(gt=-1, lt=0.5, description="Poisson's ratio")
    yield_stress: float | None = pydantic.Field(default=None, gt=0, description="Y (Pa)")
    hardening_modulus: float | None = pydantic.Field(default=None, ge=0,
                                                     description="H = d sigma_y / dp (Pa)")
    hardening: list[Annotated[list[float], pydantic.Field(min_length=2, max_length=2)]] | None = None

    @pydantic.field_validator("hardening_modulus", "hardening")
    @classmethod
    def _needs_yield(cls, value, info):
        if value is not None and info.data.get("yield_stress") is None:
            raise ValueError("needs yield_stress (Pa) in the same table")
        return value

    @pydantic.field_validator("hardening")
    @classmethod
    def _table(cls, table, info):
        if table is None:
            return table
        if info.data.get("hardening_modulus") is not None:
            raise ValueError("give hardening_modulus or the table hardening, not both")
        strains = [e for e, _ in table]
        stresses = [s for _, s in table]
        if not table or strains[0] != 0 or stresses[0] != info.data["yield_stress"]:
            raise ValueError("the first pair must be (0, yield_stress): [[0.0, "
                             f"{info.data['yield_stress']:g}], ...]")
        if any(b <= a for a, b in zip(strains, strains[1:])):
            raise ValueError("the plastic strains must increase strictly")
        if any(b < a for a, b in zip(stresses, stresses[1:])):
            raise ValueError("the yield stresses must not decrease (no softening)")
        return table

    @property
    def hardening_curve(self) -> tuple[list[float], list[float], float]:
        """(plastic strains, yield stresses (Pa), slope beyond the last point (Pa)), the form
        the compiled return map reads (fem.plasticity.hardening_tables)."""
        if self.hardening is not None:
            return [e for e, _ in self.hardening], [s for _, s in self.hardening], 0.0
        return [0.0], [self.yield_stress], self.hardening_modulus or 0.0


class Materials(Strict):
    pin: Material
    bore: Material

    @property
    def plastic(self) -> bool:
        """Whether either body can yield."""
        return self.pin.yield_stress is not None or self.bore.yield_stress is not None


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


SECOND_STAGES = ("rotation_deg", "tangential_push", "tilt_deg")   # after the push, one of them


@dataclass(frozen=True)
class Unload:
    """A load-programme item: move the hub back until its force returns to zero, in about
    `steps` steps (fem.solver.LoadStepper finds the approach where the contact opens)."""

    steps: int


@dataclass(frozen=True)
class Reload:
    """A load-programme item: push again from where the last unloading ended to `approach`
    (m), in `steps` equal steps."""

    approach: float
    steps: int


class Load(Strict):
    """The hub moves the clearance through free space, then pushes max_approach further, in
    equal steps, or in geometric steps from first_approach when that is given.

    Then, optionally, with the approach held, the hub turns the pin about its axis by
    rotation_deg, or pushes it across the load direction by tangential_push (m, towards
    +90 deg from the load), in slide_steps equal steps: the pin sticks, then slips; or (3D)
    tilts it by tilt_deg in tilt_steps equal steps, about the axis normal to the load and to
    the pin's axis through the bore's mid-plane centre (positive: the end z = length turns
    towards the load; the tilt is a load here, added to the geometry's fixed tilt_deg).
    Rotations are small-strain (linearised): r phi^2 / 2 must stay below 1 % of the approach,
    r the largest distance of a hub point from the rotation's axis.
    """

    max_approach: float = pydantic.Field(ge=0, description="hub displacement beyond first touch (m)")
    steps: int = pydantic.Field(ge=1, le=10_000)
    direction_deg: float = pydantic.Field(ge=-360, le=360)
    first_approach: float | None = pydantic.Field(default=None, gt=0)
    rotation_deg: float | None = None
    tangential_push: float | None = None
    slide_steps: int = pydantic.Field(default=10, ge=1, le=10_000)
    tilt_deg: float | None = None
    tilt_steps: int = pydantic.Field(default=10, ge=1, le=10_000)
    unload: bool = False
    unload_steps: int | None = pydantic.Field(default=None, ge=1, le=10_000)
    cycles: int = pydantic.Field(default=1, ge=1, le=1000)

    @pydantic.model_validator(mode="after")
    def _steps(self):
        given = [key for key in SECOND_STAGES if getattr(self, key) is not None]
        slide = given[0] if given else None
        if self.max_approach <= 0:
            raise ValueError("max_approach must be > 0 (m)"
                             + (f": {slide} needs a radial push first" if slide else ""))
        if len(given) > 1:
            raise ValueError(f"give one of {', '.join(SECOND_STAGES)}, not {' and '.join(given)}")
        if slide is not None and getattr(self, slide) == 0:
            raise ValueError(f"{slide} must not be 0 (leave it out for a push only)")
        if self.first_approach is not None and (self.first_approach >= self.max_approach
                                                or self.steps < 2):
            raise ValueError("first_approach must be below max_approach, with steps >= 2")
        if self.cycles > 1 and not self.unload:
            raise ValueError("cycles > 1 needs unload = true (a cycle ends at zero force)")
        if self.unload_steps is not None and not self.unload:
            raise ValueError("unload_steps applies to unload = true only")
        if self.unload and slide is not None:
            raise ValueError(f"unload: a load programme unloads after the push, not after {slide}")
        return self

    @property
    def approaches(self) -> list[float]:
        """The approach (m) of every load step of the radial push."""
        if self.first_approach is None:
            return [self.max_approach * (k + 1) / self.steps for k in range(self.steps)]
        ratio = (self.max_approach / self.first_approach) ** (1 / (self.steps - 1))
        return [self.first_approach * ratio**k for k in range(self.steps)]

    @property
    def programme(self) -> list:
        """Every load step as (approach (m), rotation (rad), tangential push (m), tilt (rad));
        with `unload`, each cycle ends with an Unload and the next reloads (Reload)."""
        points = [(a, 0.0, 0.0, 0.0) for a in self.approaches]
        if self.unload:
            unload = Unload(self.unload_steps or self.steps)
            return points + [unload] + [Reload(self.max_approach, self.steps), unload] * (self.cycles - 1)
        end = (0.0, math.radians(self.rotation_deg or 0.0), self.tangential_push or 0.0,
               math.radians(self.tilt_deg or 0.0))
        n = self.tilt_steps if self.tilt_deg is not None else self.slide_steps
        if any(end):
            points += [(self.max_approach, *(v * k / n for v in end[1:])) for k in range(1, n + 1)]
        return points

    @property
    def step_count(self) -> int:
        """The load steps of the programme as planned (an unloading's search for zero force
        counts as one)."""
        return sum(item.steps if isinstance(item, (Unload, Reload)) else 1 for item in self.programme)

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
    compliance: bool = pydantic.Field(default=False, description=(
        "write compliance.csv, the bodies' surface compliance (fem.compliance: one more solve): "
        "the kernel a worn joint's contact is solved on (a wear scene's compliance_file); a 2D "
        "elastic round joint's only"))


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
        if self.output.compliance and (self.geometry.dim != 2 or self.materials.plastic
                                       or self.geometry.wear_file is not None):
            raise ValueError("output.compliance: the surface compliance is a 2D elastic round "
                             "joint's (dim = 2, no yield_stress, no wear_file)")
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
        g, load = self.geometry, self.load
        if load.tilt_deg is not None:
            if g.dim == 2:
                raise ValueError("load.tilt_deg applies to dim = 3 only")
            if self.mesh.symmetry:
                raise ValueError("mesh.symmetry: a tilt load is not symmetric about the mid-plane")
            reach = load.max_approach + abs(math.radians(load.tilt_deg)) * (g.length / 2 + g.pin_overhang)
            if reach >= g.pin_radius - g.hub_radius:
                raise ValueError(f"load.tilt_deg: the tilt pushes the pin's end {reach:.3g} m into "
                                 "the bore, more than the pin wall (small strain)")
        for key, arm in (("rotation_deg", g.pin_radius), ("tilt_deg", self.tilt_arm)):
            if getattr(load, key) is None:
                continue
            phi = math.radians(getattr(load, key))
            if arm * phi**2 / 2 > 0.01 * load.max_approach:
                limit = math.degrees(math.sqrt(0.02 * load.max_approach / arm))
                raise ValueError(f"load.{key}: |{key[:-4]}| must be <= {limit:.3g} deg here "
                                 f"(small-strain rotation: r phi^2/2 <= 1 % of max_approach, "
                                 f"r = {arm:.3g} m)")
        check_cells(self.geometry, self.sizing, self.mesh_options)
        return self

    @property
    def tilt_arm(self) -> float:
        """The largest distance (m) of a hub point from the tilt axis (3D)."""
        g = self.geometry
        return math.hypot(g.hub_radius, (g.length or 0.0) / 2 + g.pin_overhang)

    @property
    def tilt_pivot(self) -> tuple[float, float, float]:
        """The bore's mid-plane centre (m), the point the tilt turns about and the tilting
        moment is taken about (3D)."""
        return (0.0, 0.0, (self.geometry.length or 0.0) / 2)

    @property
    def tilt_axis(self) -> tuple[float, float, float]:
        """The tilt axis: e_z x load direction, normal to the load and to the pin's axis; a
        positive tilt about it turns the end z = length towards the load (3D)."""
        d = self.load.direction
        return (-d[1], d[0], 0.0)

    @property
    def mesh_options(self) -> MeshOptions:
        """The mesh table, with the symmetry left to the mesher unless a tilt load breaks it."""
        if self.load.tilt_deg is not None and self.mesh.symmetry is None:
            return self.mesh.model_copy(update={"symmetry": False})
        return self.mesh

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

    def sizing_of(self, worn=None) -> Sizing:
        """`sizing`, or that of its worn joint (a meshes.worn.WornJoint: its wear_file read)."""
        if worn is None:
            return self.sizing
        return worn.sizing(self.joint, self.load.direction_deg, self.load.max_approach, self.mesh)

    @property
    def effective_modulus(self) -> float:
        """E* with 1/E* = (1-nu_pin^2)/E_pin + (1-nu_bore^2)/E_bore (Pa), plane strain."""
        return self.joint.e_star


def worn_joint(scene: FemScene, base, source: str):
    """The worn joint of a scene whose geometry names a wear_file (meshes.worn.WornJoint; the
    file relative to `base`, the scene's folder), its mesh's cells checked; None for a new
    joint. Bad input is one InputError line naming `source` and the key."""
    g = scene.geometry
    if g.wear_file is None:
        return None
    worn = read_worn(g, named_file(g.wear_file, base), f"{source}: geometry.wear_file ({g.wear_file})")
    try:
        check_cells(worn.base_geometry(g), scene.sizing_of(worn), scene.mesh_options)
    except ValueError as err:
        raise InputError(f"{source}: {err} (the worn joint's mesh)") from None
    return worn
