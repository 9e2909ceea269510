"""Archard's law of sliding wear [Archard1953]: the volume a surface loses is V = K W s / H
(K the dimensionless wear coefficient, W the normal load, s the distance slid, H the
hardness of the softer surface). Locally, on a surface under the contact pressure p sliding
at the speed v_s, the depth worn grows as

    dh/dt = k p |v_s|,    k = K / H  (m^2/N, the dimensional wear coefficient, m^3/(N m)),

which integrated over a flat contact of area A (p A = W) is Archard's V = k W s. The form
of [Flores2009] and of [Mukras2010] (on the FE contact pressure).
"""

import numpy as np


def archard_depth_rate(pressure, sliding_speed, coefficient: float):
    """dh/dt = k p |v_s| (m/s): the depth a surface loses per second under the contact
    pressure p (Pa) sliding at v_s (m/s), k (m^2/N) its dimensional wear coefficient
    [Archard1953]."""
    return coefficient * np.asarray(pressure, dtype=float) * np.abs(sliding_speed)
