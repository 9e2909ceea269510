"""The geometry and meshing tables of a scene, and the physical-group tags every stage uses."""

from typing import Literal

import pydantic

from pinbore.scene import Strict

# Physical groups (cells of each body, facets of each boundary). Stages downstream use these.
PIN, HOUSING = 1, 2
HUB, PIN_SURFACE, BORE_SURFACE, HOUSING_EDGE = 11, 12, 13, 14
PIN_ENDS, HOUSING_ENDS = 15, 16  # 3D only: the planes z = 0 and z = length


class Geometry(Strict):
    """Pin (with a rigid hub) inside the bore of an annular housing; SI units (m)."""

    dim: Literal[2, 3]
    pin_radius: float = pydantic.Field(gt=0)
    bore_radius: float = pydantic.Field(gt=0)
    housing_radius: float = pydantic.Field(gt=0)
    hub_radius: float = pydantic.Field(gt=0)
    length: float | None = pydantic.Field(default=None, gt=0)

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.bore_radius <= self.pin_radius:
            raise ValueError("bore_radius must exceed pin_radius (clearance > 0)")
        if self.hub_radius >= self.pin_radius:
            raise ValueError("hub_radius must be smaller than pin_radius")
        if self.housing_radius <= self.bore_radius:
            raise ValueError("housing_radius must exceed bore_radius")
        if self.dim == 3 and self.length is None:
            raise ValueError("length is required when dim = 3")
        return self

    @property
    def clearance(self) -> float:
        """Radial clearance c = R_bore - R_pin (m)."""
        return self.bore_radius - self.pin_radius


class MeshOptions(Strict):
    """Element sizes. Left out, pinbore chooses them from the expected contact arc.

    contact_size (m) on the contact arc; grading: growth of the size per unit distance from
    it; refine: halve every element size this many times (convergence studies); layers: 3D
    layers along the axis.
    """

    contact_size: float | None = pydantic.Field(default=None, gt=0)
    grading: float = pydantic.Field(default=0.25, gt=0, le=1)
    refine: int = pydantic.Field(default=0, ge=0, le=6)
    layers: int | None = pydantic.Field(default=None, ge=1)
