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


@dataclass(frozen=True)
class Sizing:
    """Element size on the arc (m), the arc's half-angle (rad), the growth rate away from it,
    and a factor on every size (1/2^refine)."""

    contact_size: float
    arc_half_angle: float
    grading: float
    scale: float = 1.0


def estimate_sizing(joint: Joint, max_approach, contact_size=None, grading=0.25, refine=0):
    """Sizing for `joint` pushed `max_approach` (m) beyond first touch."""
    def half_angle(d):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Johnson out of its range: Liu decides
            force = np.nanmax([float(liu(d, joint)), float(johnson(d, joint))])
        return persson_half_angle(force / (joint.e_star * joint.clearance))

    if contact_size is None:
        contact_size = joint.r_bore * min(math.sin(half_angle(0.1 * max_approach)) / 20,
                                          math.radians(0.5))
    arc = min(math.radians(95),
              1.5 * half_angle(max_approach) + math.radians(5) + 4 * contact_size / joint.r_bore)
    scale = 0.5**refine
    return Sizing(contact_size * scale, arc, grading * scale, scale)
