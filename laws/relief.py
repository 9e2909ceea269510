"""Edge relief of a bore: how much wider than the cylinder the bore is near its end faces.

Over `length` l (m) from each end the bore's radius grows along a circular arc tangent to the
cylinder, to `depth` d (m) more at the end face. At a distance x into the relieved zone
(x = l - (distance to the nearer end), 0 <= x <= l) the extra radius is the arc's sagitta

    r(x) = R - sqrt(R^2 - x^2),   R = (l^2 + d^2) / (2 d)   (m),

R the arc's radius (r(l) = d fixes it). Plain geometry; the FE contact (pinbore.fem.contact)
sees this exact profile, the sliced joint law (pinbore.laws.sliced) the same formula, compiled
here once for both. Compiled on first use (core.compiled.compile_on_use): a scene that names a
relief validates without loading numba.
"""

import math
from dataclasses import dataclass

import numpy as np

from pinbore.core.compiled import compile_on_use


def relief_at(z, z_low, z_high, length, depth):
    """Extra radius r (m), its slope dr/dz (-) and curvature d2r/dz2 (1/m) at the axial
    position z of a bore spanning z_low <= z <= z_high, relieved over `length` (m) from each
    end to `depth` (m) at the faces (formula: module docstring). Zero outside the relieved
    zones; the slope is negative towards z_low."""
    r = (length**2 + depth**2) / (2 * depth)
    into = min(max(length - min(z - z_low, z_high - z), 0.0), length)
    side = -1.0 if z - z_low < z_high - z else 1.0                       # d(into)/dz
    root = math.sqrt(r**2 - into**2)
    return r - root, side * into / root, r**2 / root**3 if into > 0 else 0.0


def relief_profile(z, z_low, z_high, length, depth):
    """`relief_at` at every point of the 1-D array z: three arrays (m, -, 1/m)."""
    out = np.empty((3, z.size))
    for k in range(z.size):
        out[0, k], out[1, k], out[2, k] = relief_at(z[k], z_low, z_high, length, depth)
    return out


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
        out = __getattr__("relief_profile")(z.ravel(), float(z_low), float(z_high), self.length,
                                          self.depth)
        return tuple(a.reshape(z.shape) for a in out)


__getattr__ = compile_on_use(globals(), {"relief_at": {"cache": True},
                                         "relief_profile": {"cache": True}})
