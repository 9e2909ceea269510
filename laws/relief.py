"""Edge relief of a bore: how much wider than the cylinder the bore is near its end faces.

Over `length` l (m) from each end the bore's radius grows along a circular arc tangent to the
cylinder, to `depth` d (m) more at the end face. At a distance x into the relieved zone
(x = l - (distance to the nearer end), 0 <= x <= l) the extra radius is the arc's sagitta

    r(x) = R - sqrt(R^2 - x^2),   R = (l^2 + d^2) / (2 d)   (m),

R the arc's radius (r(l) = d fixes it). Plain geometry; the FE contact (pinbore.fem.contact)
sees this exact profile, the sliced joint law (pinbore.laws.sliced) the same formula, the
compiled core's (cpp/mechanism/laws.h) once for both.
"""

from dataclasses import dataclass

import numpy as np

from pinbore.core.cpp import laws as _core


# the extra radius, its slope and curvature at z (relief_at) and at every point of an array
# (relief_profile: (3, n)): the compiled core's (cpp/mechanism/laws.h), which the sliced law
# evaluates in the multibody engine
relief_at = _core.relief_at
relief_profile = _core.relief_profile


@dataclass(frozen=True)
class Relief:
    """Edge relief of the bore: over `length` (m) from each end the bore radius grows along a
    circular arc, tangent to the bore, to `depth` (m) more at the end face; the arc's radius
    is r = (length^2 + depth^2) / (2 depth)."""

    length: float
    depth: float

    def profile(self, z, z_low, z_high):
        """delta(z), delta'(z), delta''(z) (m, -, 1/m) of the bore between z_low and z_high."""
        z = np.asarray(z, dtype=float)
        out = relief_profile(np.ascontiguousarray(z.ravel()), float(z_low), float(z_high),
                             self.length, self.depth)
        return tuple(a.reshape(z.shape) for a in out)
