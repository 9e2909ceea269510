"""The vectors of a mechanism scene: a planar one's [x, y], a spatial one's [x, y, z], Euler
parameters and 3 x 3 matrices (rows), and the unit axis of a vector; the scene, the clearance
joints and the body kinds read them here."""

import math
from typing import Annotated

import pydantic

Vector = Annotated[list[float], pydantic.Field(min_length=2, max_length=2)]
Vector3 = Annotated[list[float], pydantic.Field(min_length=3, max_length=3)]
Quaternion = Annotated[list[float], pydantic.Field(min_length=4, max_length=4)]
Matrix3 = Annotated[list[Vector3], pydantic.Field(min_length=3, max_length=3)]


def unit_axis(v, key):
    """v (a nonzero axis) normalised; one rule line otherwise."""
    n = math.sqrt(sum(c * c for c in v))
    if n == 0:
        raise ValueError(f"{key}: an axis must have nonzero length")
    return [c / n for c in v]
