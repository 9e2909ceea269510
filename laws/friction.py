"""Friction laws for the tangential force at a contact, as scalar functions compiled with numba:
the multibody engine (the compiled core, cpp/mechanism/laws.h) evaluates their C++ forms inside its
right-hand side, and the tests check them against closed forms.

v is the slip velocity (m/s). Every law gives F, the friction force along the slip: the
sliding body feels -F, which opposes it. sgn v is 1 for v > 0 and -1 otherwise (at v = 0 the
regularised laws vanish and Dahl's rate is zero). Static laws give F, or the coefficient mu
that Ambrosio's regularised Coulomb force turns into F; the state-variable laws (Dahl,
LuGre, Iwan) give the rates of their states, which the integrator carries. Sources as in
[Cao2013] (its eqs. 12-20) and the primary sources named in each docstring (keys of
REFERENCES.md).
"""

import math

import numba


@numba.njit(cache=True)
def sgn(v):
    """sgn v = 1 for v > 0, -1 otherwise."""
    return 1.0 if v > 0 else -1.0


@numba.njit(cache=True)
def coulomb(v, normal, mu):
    """Den Hartog 1931 [DenHartog1931] ([Cao2013] eq. 12, there as the force on the body, -F):
    F = mu F_N sgn v."""
    return mu * normal * sgn(v)


@numba.njit(cache=True)
def ambrosio_factor(v, v0, v1):
    """Ambrosio 2003 [Ambrosio2003]: c_d = 0 for |v| <= v0, (|v| - v0)/(v1 - v0) up to v1, 1 above."""
    speed = abs(v)
    return 0.0 if speed <= v0 else (speed - v0) / (v1 - v0) if speed <= v1 else 1.0


@numba.njit(cache=True)
def ambrosio(v, normal, mu, v0, v1):
    """Ambrosio 2003 [Ambrosio2003], regularised Coulomb: F = mu c_d(|v|) F_N sgn v, continuous at v = 0.
    mu may depend on the slip (stribeck_polynomial, linear_velocity)."""
    return coulomb(v, normal, mu * ambrosio_factor(v, v0, v1))


@numba.njit(cache=True)
def stribeck_polynomial(v, mu_s, mu_m, v_m):
    """Thomsen & Fidlin 2003 [ThomsenFidlin2003] ([Cao2013] eq. 14): the coefficient
    mu(|v|) = mu_s - k1 |v| + k3 |v|^3, k1 = 1.5 (mu_s - mu_m)/v_m, k3 = 0.5 (mu_s - mu_m)/v_m^3,
    equal to mu_s at v -> 0 and to its minimum mu_m at |v| = v_m, where its slope is zero.
    The polynomial was fitted below v_m; beyond it, it rises again as |v|^3 (back to mu_s at
    sqrt(3) v_m, then without bound), which is no friction law: pinbore holds mu = mu_m for
    |v| >= v_m, the kinetic coefficient, continuous with its slope (C1) at v_m."""
    speed = abs(v)
    if speed >= v_m:
        return mu_m
    k = mu_s - mu_m
    return mu_s - 1.5 * k / v_m * speed + 0.5 * k / v_m**3 * speed**3


@numba.njit(cache=True)
def linear_velocity(v, mu_s, alpha):
    """[Cao2013] eq. 15: mu = mu_s + alpha |v| (alpha in s/m)."""
    return mu_s + alpha * abs(v)


@numba.njit(cache=True)
def dahl_rate(force, v, sigma, f_c, alpha=1.0):
    """Dahl 1976 [Dahl1976] ([Cao2013] eq. 16): dF/dt = sigma (1 - (F / F_c) sgn v)^alpha v,
    sigma in N/m. For alpha = 1 at constant v > 0 from F = 0: F = F_c (1 - exp(-sigma x / F_c)),
    x = v t. Divided by the normal force (F = F_N m, F_c = mu F_N, sigma / F_N in 1/m) it is
    the rate of m. Where |F| exceeds F_c (a normal force that drops) the base is negative,
    and a real power of it has no value for alpha != 1: the power is taken of |base| with the
    base's sign, |b|^alpha sgn b (Dahl's symmetric form), which pulls F back to F_c."""
    base = 1.0 - force / f_c * sgn(v)
    return sigma * abs(base) ** alpha * math.copysign(1.0, base) * v


@numba.njit(cache=True)
def lugre_g(v, f_c, f_s, v_s):
    """LuGre (Canudas de Wit et al. 1995 [CanudasDeWit1995], [Cao2013] eq. 18):
    g(v) = F_c + (F_s - F_c) exp(-(v/v_s)^2), carrying force units (sigma0 g in [Cao2013]'s
    notation); normalised by the normal force, F_c and F_s are coefficients."""
    return f_c + (f_s - f_c) * math.exp(-(v / v_s) ** 2)


@numba.njit(cache=True)
def lugre_rate(z, v, sigma0, g):
    """LuGre bristle state ([Cao2013] eq. 17): dz/dt = v - sigma0 |v| z / g(v)."""
    return v - sigma0 * abs(v) * z / g


@numba.njit(cache=True)
def lugre_force(z, z_rate, v, sigma0, sigma1, sigma2):
    """LuGre friction force F = sigma0 z + sigma1 dz/dt + sigma2 v. Steady sliding:
    F = g(v) sgn v + sigma2 v."""
    return sigma0 * z + sigma1 * z_rate + sigma2 * v


@numba.njit(cache=True)
def iwan_bilinear(travel, stretch, v, k1, k2, f_cr):
    """Bilinear Iwan element ([Iwan1966]; [Cao2013] eq. 13): a Jenkins element (spring k1 in series
    with a Coulomb slider of strength F_cr) in parallel with a spring k2. States: the travel x
    and the Jenkins spring's stretch z. F = k1 z + k2 x; x' = v; z' = v while the slider
    sticks, 0 while it slides (|k1 z| = F_cr, z v > 0); between steps iwan_return_map holds
    |k1 z| <= F_cr. Returns (F, x', z')."""
    limit = f_cr / k1
    z = min(max(stretch, -limit), limit)
    sliding = abs(stretch) >= limit and stretch * v > 0
    return k1 * z + k2 * travel, v, 0.0 if sliding else v


@numba.njit(cache=True)
def iwan_return_map(stretch, k1, f_cr):
    """The Iwan element's slider after a step: a stretch beyond |k1 z| = F_cr is the slider
    moving, so z returns to the limit (return mapping)."""
    limit = f_cr / k1
    return math.copysign(limit, stretch) if abs(stretch) > limit else stretch
