"""The impact scene (`kind = "impact"`, `pinbore impact SCENE --out DIR`): the pin flies into
the bore at an impact speed and rebounds.

The bodies are those of the FE scene (fem.scene): the same geometry, contact and mesh
tables, materials with a density. What moves:

- the pin: an elastic annulus pin_radius > r > hub_radius of density `materials.pin.density`
  (kg/m^3), around a rigid hub r < hub_radius. The hub is the pin's own core: its mass
  rho_pin pi hub_radius^2 (kg/m, plane strain: per unit length) plus `impact.hub_mass`
  (kg/m, what the link carrying the pin adds) moves as one rigid body that translates (its
  rotation is held: a pin guided by its link). The pin's mass m = rho_pin pi pin_radius^2 +
  hub_mass is what flies in;
- the housing: an elastic annulus of density `materials.bore.density`, clamped at its outer
  edge as in the quasi-static runs.

Either body yields where its material has a `yield_stress` (von Mises, isotropic hardening:
`hardening_modulus` or a `hardening` table, exactly as in the FE scene; fem.plasticity); the
plastic work then enters the energy book.

At t = 0 the pin sits `impact.initial_gap` short of touching the bore along
`impact.direction_deg` (below the diametral clearance 2c: the pin inside its bore) and moves
at `impact.speed` (m/s, v0 > 0) along it; nothing else moves and nothing is loaded.

Before meshing, the impact is estimated on Liu's law (laws.elastic.liu, within tens of
percent of the FE force in conformal contact: see README, Calibration) with the mass m:
the largest approach d_m, which sizes the mesh as the quasi-static `max_approach` does, and
the contact duration t_c, which sets the time step (t_c / `steps_per_contact`, or
`time_step`). A time step above t_c / MIN_STEPS_PER_CONTACT cannot resolve the contact and
is refused before running.
"""

import functools
import math
from typing import Literal

import pydantic

from pinbore.core.scene import Strict
from pinbore.fem.scene import Contact, FemScene, Material, Output, Solver
from pinbore.laws import dissipative, elastic
from pinbore.meshes.model import Geometry, MeshOptions

MIN_STEPS_PER_CONTACT = 10     # fewer steps than this over the estimated contact: refused
APPROACH_MARGIN = 1.3          # the mesh is sized for this multiple of the estimated d_m
INITIAL_GAP_STEPS = 5          # default flight before contact, in time steps
MAX_DEFAULT_GAP = 1.5          # ... but at most this many clearances c (below 2c: inside the bore)


class DynamicMaterial(Material):
    """The FE scene's material (linear elastic, or elasto-plastic with `yield_stress` and
    `hardening_modulus` or a `hardening` table, validated alike), with a mass density."""

    density: float = pydantic.Field(gt=0, description="mass density (kg/m^3)")


class DynamicMaterials(Strict):
    pin: DynamicMaterial
    bore: DynamicMaterial


class Impact(Strict):
    """The impact: speed v0 (m/s) along direction_deg, the hub's added mass (kg/m), the time
    integration (fem.impact.solver: the WBZ member of the generalized-alpha family with spectral
    radius rho_inf at infinite frequency: 1, the default, is the trapezoidal rule and
    conserves the energy of the linear part exactly, below 1 damps the frequencies near
    1/dt), the time step (s) or the steps over the estimated contact duration, the flight
    before contact (m), how long (in estimated contact durations) the run may last before it
    is called incomplete, the energy control of the step (adaptive_steps: a step whose
    contact integration loses or makes more than energy_tolerance E_0 / steps_per_contact is
    repeated smaller, so the energy book closes to about energy_tolerance of E_0;
    fem.impact.solver) and the mass of the contact surfaces' nodes (fem.impact.solver)."""

    speed: float = pydantic.Field(gt=0, description="impact speed v0 (m/s)")
    direction_deg: float = pydantic.Field(ge=-360, le=360)
    hub_mass: float = pydantic.Field(default=0.0, ge=0, description="added rigid mass (kg/m)")
    spectral_radius: float = pydantic.Field(default=1.0, ge=0, le=1)
    time_step: float | None = pydantic.Field(default=None, gt=0)
    steps_per_contact: int = pydantic.Field(default=100, ge=MIN_STEPS_PER_CONTACT, le=100_000)
    initial_gap: float | None = pydantic.Field(default=None, ge=0)
    max_contact_durations: float = pydantic.Field(default=6.0, gt=1)
    energy_tolerance: float = pydantic.Field(default=1e-3, gt=0, lt=1)
    adaptive_steps: bool = True
    surface_mass: Literal["redistributed", "consistent"] = "redistributed"

    @property
    def direction(self) -> tuple[float, float]:
        a = math.radians(self.direction_deg)
        return (math.cos(a), math.sin(a))


class ImpactOutput(Strict):
    picture: bool = True


class ImpactScene(Strict):
    kind: Literal["impact"]
    geometry: Geometry
    materials: DynamicMaterials
    contact: Contact
    impact: Impact
    mesh: MeshOptions = MeshOptions()
    solver: Solver = Solver()
    output: ImpactOutput = ImpactOutput()

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.geometry.dim != 2:
            raise ValueError("geometry.dim: the impact runs in plane strain (dim = 2) only")
        if self.geometry.wear_file is not None:
            raise ValueError("geometry.wear_file: the impact runs on a new joint (the FE of a "
                             "worn one is `pinbore fem`'s)")
        estimate = self.estimate
        if estimate.max_approach >= self.geometry.pin_radius - self.geometry.hub_radius:
            raise ValueError(f"impact.speed: the estimated approach {estimate.max_approach:.3g} m "
                             "exceeds the pin wall (small strain)")
        if self.dt > estimate.duration / MIN_STEPS_PER_CONTACT:
            raise ValueError(f"impact.time_step: must be <= {estimate.duration / MIN_STEPS_PER_CONTACT:.3g} s "
                             f"(estimated contact duration {estimate.duration:.3g} s on Liu's "
                             f"law / {MIN_STEPS_PER_CONTACT} steps); got {self.dt:.3g} s")
        diametral = 2 * self.geometry.clearance
        if self.impact.initial_gap is not None and self.impact.initial_gap >= diametral:
            raise ValueError(f"impact.initial_gap: {self.impact.initial_gap:.3g} m short of touching "
                             f"puts the pin through the far side of the bore: it must be below the "
                             f"diametral clearance 2c = {diametral:.3g} m")
        self.equivalent_fem_scene   # the geometry, mesh and contact rules of the FE scene
        return self

    @property
    def pin_mass(self) -> float:
        """m = rho_pin pi R_pin^2 + hub_mass (kg/m): the elastic annulus, its rigid core and
        the added mass."""
        return (self.materials.pin.density * math.pi * self.geometry.pin_radius**2
                + self.impact.hub_mass)

    @property
    def impact_energy(self) -> float:
        """m v0^2 / 2 (J/m)."""
        return 0.5 * self.pin_mass * self.impact.speed**2

    @functools.cached_property
    def estimate(self) -> dissipative.Impact:
        """The impact of the mass m on Liu's law (N/m), before any FE: duration and d_m."""
        joint = self.equivalent_joint
        return dissipative.impact(lambda d, rate: float(elastic.liu(max(d, 0.0), joint)),
                                  self.pin_mass, self.impact.speed)

    @property
    def equivalent_joint(self) -> elastic.Joint:
        g, pin, bore = self.geometry, self.materials.pin, self.materials.bore
        return elastic.Joint(g.bore_radius, g.pin_radius, bore.E, bore.nu, pin.E, pin.nu, 1.0)

    @property
    def dt(self) -> float:
        """The time step (s): time_step, or the estimated duration / steps_per_contact."""
        return self.impact.time_step or self.estimate.duration / self.impact.steps_per_contact

    @property
    def initial_gap(self) -> float:
        """Flight (m) before first touch: initial_gap, or INITIAL_GAP_STEPS steps at v0 but
        at most MAX_DEFAULT_GAP c (the pin starts clear of the far side of the bore by c/2: a
        flight of 2c or more would start it through that side)."""
        if self.impact.initial_gap is not None:
            return self.impact.initial_gap
        return min(INITIAL_GAP_STEPS * self.dt * self.impact.speed,
                   MAX_DEFAULT_GAP * self.geometry.clearance)

    @functools.cached_property
    def equivalent_fem_scene(self) -> FemScene:
        """The quasi-static FE scene of the same bodies, contact and mesh, pushed along the
        impact direction to APPROACH_MARGIN times the estimated largest approach: it sizes
        the mesh (`pinbore fem` on it meshes alike) and gives the quasi-static curve."""
        materials = {name: m.model_dump(exclude_none=True, exclude={"density"})
                     for name, m in (("pin", self.materials.pin), ("bore", self.materials.bore))}
        return FemScene.model_validate({
            "kind": "fem", "geometry": self.geometry.model_dump(exclude_defaults=True),
            "materials": materials, "contact": self.contact.model_dump(exclude_none=True),
            "load": {"max_approach": APPROACH_MARGIN * self.estimate.max_approach, "steps": 10,
                     "direction_deg": self.impact.direction_deg},
            "mesh": self.mesh.model_dump(exclude_none=True),
            "solver": self.solver.model_dump(), "output": {"picture": False}})

    @property
    def effective_modulus(self) -> float:
        return self.equivalent_fem_scene.effective_modulus
