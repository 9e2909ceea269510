"""The scene of `pinbore modes`: a body (meshes.body), its material, and the reduction to a
flexible body of a mechanism (fem.modes.reduction). Read without DOLFINx or Gmsh.

    [body]        shape, dim, length, width, thickness, cell_size, ... (meshes.body)
    [material]    E (Pa), nu, density (kg/m^3)
    [reduction]   interfaces = ["a", "b"]    the joints' interfaces: the reduction's boundary
                  fixed_interface_modes = 12  normal modes with those interfaces held
                  modes = 6                   the flexible modes the body keeps
                  degree = 2                  Lagrange degree of the FE space
"""

from typing import Literal

import pydantic

from pinbore.core.scene import Strict
from pinbore.meshes.body import BodyGeometry


class Material(Strict):
    """Isotropic, linear elastic, with its density."""

    # the ranges of solid materials, which the FE forms and SLEPc take (E = 1e-300 or
    # density = 1e300 failed inside SLEPc; E = 1e300 in the compiled form's code)
    E: float = pydantic.Field(ge=1e3, le=1e13, description="Young's modulus (Pa): 1e3-1e13")
    nu: float = pydantic.Field(gt=-1, lt=0.5, description="Poisson's ratio")
    density: float = pydantic.Field(ge=0.1, le=1e5, description="kg/m^3: 0.1-1e5")


class Reduction(Strict):
    """Craig-Bampton with rigid interfaces, then the reduced body's own free modes
    (fem.modes.reduction)."""

    interfaces: list[str] = pydantic.Field(min_length=1)
    fixed_interface_modes: int = pydantic.Field(ge=1, le=200)
    modes: int = pydantic.Field(ge=1, le=200)
    degree: Literal[1, 2] = 2
    stiffening_held: list[str] | None = pydantic.Field(default=None, description=(
        "the interfaces that carry the centrifugal load of the geometric stiffening, the body "
        "turning about the first of them (default: the first interface alone: a link turning "
        "about its root; a panel on two hinge lugs names both)"))
    full_modes: int = pydantic.Field(default=0, ge=0, le=200, description=(
        "free modes of the whole FE model to solve beside the reduced body's, to measure "
        "the reduction's error (0: none)"))


class ModesScene(Strict):
    body: BodyGeometry
    material: Material
    reduction: Reduction

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        known = self.body.interfaces
        for k, name in enumerate(self.reduction.interfaces):
            if name not in known:
                raise ValueError(f"reduction.interfaces.{k}: {name!r} is not an interface of "
                                 f"this {self.body.shape} (it has {', '.join(known)})")
        held = self.reduction.stiffening_held
        if held is not None:
            if not held or len(set(held)) != len(held):
                raise ValueError("reduction.stiffening_held: one interface or more, each once")
            for k, name in enumerate(held):
                if name not in self.reduction.interfaces:
                    raise ValueError(f"reduction.stiffening_held.{k}: {name!r} is not one of "
                                     "reduction.interfaces")
        if len(set(self.reduction.interfaces)) != len(self.reduction.interfaces):
            raise ValueError("reduction.interfaces: an interface is named twice")
        most = self.most_modes
        if self.reduction.modes > most:
            raise ValueError(f"reduction.modes: {self.reduction.modes} is more than the reduced "
                             f"body can give ({most}: fixed_interface_modes + {self.rigid} per "
                             f"interface less the {self.rigid} rigid-body motions)")
        return self

    @property
    def rigid(self) -> int:
        """Rigid-body motions of the body, and the coordinates of an interface's frame: 3 in
        the plane (x, y, theta_z), 6 in space."""
        return 3 if self.body.dim == 2 else 6

    @property
    def held(self) -> list[str]:
        """The interfaces the stiffening's load cases hold (the first: the turning axis')."""
        return self.reduction.stiffening_held or self.reduction.interfaces[:1]

    @property
    def most_modes(self) -> int:
        r = self.reduction
        return r.fixed_interface_modes + self.rigid * (len(r.interfaces) - 1)
