"""Friction laws for the tangential force at a contact: v is the slip velocity (m/s), the force
opposes it. Static laws return the friction force (N) or coefficient; state-variable laws
(Dahl, LuGre, Iwan) return the rate or the update of their state, which an integrator carries.
Sources as in the review (its eqs. 12-20) and the formula sheet.
"""

import math

import numpy as np


def coulomb(v, normal, mu):
    """Den Hartog 1931 (review eq. 12): F = -mu F_N sgn v."""
    return -mu * normal * np.sign(v)


def ambrosio_factor(speed, v0, v1):
    """Ambrosio 2003: c_d = 0 for |v| <= v0, (|v| - v0)/(v1 - v0) up to v1, 1 above."""
    return np.clip((np.abs(speed) - v0) / (v1 - v0), 0.0, 1.0)


def ambrosio(v, normal, mu, v0, v1):
    """Ambrosio 2003, regularised Coulomb: F = -mu c_d(|v|) F_N v / |v|."""
    return -mu * ambrosio_factor(v, v0, v1) * normal * np.sign(v)


def stribeck_polynomial(v, mu_s, mu_m, v_m):
    """Thomsen & Fidlin 2003 (review eq. 14, opposite sign convention): the coefficient
    mu(v) = mu_s sgn v - k1 v + k3 v^3, k1 = 1.5 (mu_s - mu_m)/v_m, k3 = 0.5 (mu_s - mu_m)/v_m^3,
    equal to mu_s at v -> 0+ and to its minimum mu_m at |v| = v_m."""
    v = np.asarray(v, float)
    k1 = 1.5 * (mu_s - mu_m) / v_m
    k3 = 0.5 * (mu_s - mu_m) / v_m**3
    return mu_s * np.sign(v) - k1 * v + k3 * v**3


def linear_velocity(v, mu_s, alpha):
    """Review eq. 15: mu = mu_s + alpha |v| (alpha in s/m)."""
    return mu_s + alpha * np.abs(v)


def dahl_rate(force, v, sigma, f_c, alpha=1.0):
    """Dahl 1976 (review eq. 16): dF/dt = sigma (1 - (F / F_c) sgn v)^alpha v, sigma in N/m.
    For alpha = 1 at constant v > 0 from F = 0: F = F_c (1 - exp(-sigma x / F_c)), x = v t."""
    return sigma * (1 - force / f_c * np.sign(v)) ** alpha * v


def lugre_g(v, f_c, f_s, v_s):
    """LuGre (Canudas de Wit et al. 1995, review eq. 18): g(v) = F_c + (F_s - F_c) exp(-(v/v_s)^2),
    carrying force units (sigma0 g in the review's notation)."""
    return f_c + (f_s - f_c) * np.exp(-(np.asarray(v, float) / v_s) ** 2)


def lugre_rate(z, v, sigma0, g):
    """LuGre bristle state (review eq. 17): dz/dt = v - sigma0 |v| z / g(v)."""
    return v - sigma0 * np.abs(v) * z / g


def lugre_force(z, z_rate, v, sigma0, sigma1, sigma2):
    """LuGre friction force F = sigma0 z + sigma1 dz/dt + sigma2 v (the force the surface needs
    to slide; the slip is resisted by -F). Steady sliding: F = g(v) sgn v + sigma2 v."""
    return sigma0 * z + sigma1 * z_rate + sigma2 * v


def iwan_bilinear(x, slider, k1, k2, f_cr):
    """Bilinear Iwan element (review eq. 13): a Jenkins element (spring k1 in series with a
    Coulomb slider of strength F_cr) in parallel with a spring k2, at displacement x with the
    slider at `slider`. Returns (force, new slider position): the slider moves only as far as
    keeps |k1 (x - slider)| <= F_cr (return mapping)."""
    trial = k1 * (x - slider)
    if abs(trial) > f_cr:
        slider = x - math.copysign(f_cr, trial) / k1
        trial = math.copysign(f_cr, trial)
    return trial + k2 * x, slider
