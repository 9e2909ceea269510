"""Where to refine: the expected contact arc and the element size on it.

pinbore grades the mesh so that it is fine on the contact arc and coarse elsewhere. The arc
is not known before solving, so it is estimated from the scene, generously, and used only to
place elements (never in a result):

1. force per length at an approach d: the larger of the Liu et al. (2007) elastic-foundation
   law P = (pi/2) E* d sqrt(d / (2 (c + d))) (good for small clearance, it underestimates
   the FE force several times at c/R = 0.1) and Johnson's line contact
   d = (P / (pi E*)) [ln(4 pi E* c / P) - 1] (good for large clearance, no solution for
   small clearance);
2. contact half-angle from the Persson conformal solution
   P / (E* c) = 2 pi b^2 (1 + b^2) / (2 - ln(1 + b^2) - 2 b^4),  b = tan(eps/2);
3. the refined arc covers 1.5 eps + 5 deg at the largest approach; the element size resolves
   the contact half-width at a tenth of the largest approach with 20 elements, and is never
   coarser than 0.5 deg of arc.
"""

import math
from dataclasses import dataclass

from scipy.optimize import brentq

PERSSON_LIMIT_B = 0.913572  # b where the Persson denominator vanishes: eps -> 84.83 deg


@dataclass(frozen=True)
class Sizing:
    """Element size on the arc (m), the arc's half-angle (rad), the growth rate away from it,
    and a factor on every size (1/2^refine)."""

    contact_size: float
    arc_half_angle: float
    grading: float
    scale: float = 1.0


def persson_load(b: float) -> float:
    """Dimensionless Persson load P/(E* c) for b = tan(eps/2), 0 <= b < 0.913572."""
    b2 = b * b
    return 2 * math.pi * b2 * (1 + b2) / (2 - math.log1p(b2) - 2 * b2 * b2)


def persson_half_angle(load: float) -> float:
    """Contact half-angle eps (rad) for the dimensionless load P/(E* c) >= 0."""
    if load <= 0:
        return 0.0
    b = brentq(lambda b: persson_load(b) - load, 0.0, PERSSON_LIMIT_B * (1 - 1e-12))
    return 2 * math.atan(b)


def liu_force(e_star, clearance, d):
    """Liu et al. 2007 force per length (N/m) at approach d (estimate for sizing only)."""
    return 0.5 * math.pi * e_star * d * math.sqrt(d / (2 * (clearance + d)))


def johnson_force(e_star, clearance, d):
    """Force per length (N/m) of Johnson's equal-material line contact at approach d, or 0
    where that approach exceeds the formula's largest (at P = 4 pi E* c / e^2)."""
    def approach(p):
        return p / (math.pi * e_star) * (math.log(4 * math.pi * e_star * clearance / p) - 1)

    largest = 4 * math.pi * e_star * clearance / math.e**2
    if approach(largest) < d:
        return 0.0
    return brentq(lambda p: approach(p) - d, largest * 1e-15, largest)


def estimate_sizing(radius, clearance, e_star, max_approach, contact_size=None, grading=0.25,
                    refine=0):
    """Sizing for a pin of `radius` in a bore with `clearance`, pushed `max_approach` deep."""
    def half_angle(d):
        force = max(liu_force(e_star, clearance, d), johnson_force(e_star, clearance, d))
        return persson_half_angle(force / (e_star * clearance))

    if contact_size is None:
        contact_size = radius * min(math.sin(half_angle(0.1 * max_approach)) / 20,
                                    math.radians(0.5))
    arc = min(math.radians(95),
              1.5 * half_angle(max_approach) + math.radians(5) + 4 * contact_size / radius)
    scale = 0.5**refine
    return Sizing(contact_size * scale, arc, grading * scale, scale)
