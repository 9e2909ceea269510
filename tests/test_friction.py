"""Friction laws against closed forms: Stribeck minimum, Dahl's exponential approach, LuGre's
steady Stribeck curve and pre-sliding stiffness, the Iwan element's Masing loop. The laws are
the compiled functions the multibody kernel runs."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pinbore.laws import friction as fr

# LuGre parameters of Canudas de Wit et al. 1995, Table I
SIGMA0, SIGMA1, SIGMA2 = 1e5, math.sqrt(1e5), 0.4
F_C, F_S, V_S = 1.0, 1.5, 0.001


def test_coulomb_and_ambrosio():
    """The force on the sliding body, -F, opposes the slip."""
    assert -fr.coulomb(0.3, 100.0, 0.2) == -20.0 and -fr.coulomb(-0.3, 100.0, 0.2) == 20.0
    np.testing.assert_allclose([-fr.ambrosio(v, 100.0, 0.2, 1e-4, 1e-3) for v in (0.5e-4, 5.5e-4, 2e-3)],
                               [0.0, -10.0, -20.0])


def test_stribeck_polynomial_starts_at_mu_s_and_bottoms_at_mu_m():
    v = np.linspace(1e-9, 0.2, 200001)
    mu = np.array([fr.stribeck_polynomial(x, 0.3, 0.15, 0.05) for x in v])
    assert mu[0] == pytest.approx(0.3, abs=1e-6)
    assert v[np.argmin(mu)] == pytest.approx(0.05, rel=1e-3) and mu.min() == pytest.approx(0.15, rel=1e-9)
    assert fr.linear_velocity(-0.2, 0.3, 0.5) == pytest.approx(0.4)


def test_dahl_approaches_coulomb_exponentially():
    sigma, f_c, v = 2e4, 3.0, 0.01
    sol = solve_ivp(lambda t, f: [fr.dahl_rate(f[0], v, sigma, f_c)], (0, 0.05), [0.0],
                    rtol=1e-11, atol=1e-13, dense_output=True)
    t = np.linspace(0, 0.05, 50)
    np.testing.assert_allclose(sol.sol(t)[0], f_c * (1 - np.exp(-sigma * v * t / f_c)), atol=1e-8)


@pytest.mark.parametrize("v", [1e-4, 1e-3, 3e-3, 0.1])
def test_lugre_steady_sliding_is_the_stribeck_curve(v):
    g = fr.lugre_g(v, F_C, F_S, V_S)
    sol = solve_ivp(lambda t, z: [fr.lugre_rate(z[0], v, SIGMA0, g)], (0, 20 * g / (SIGMA0 * v)),
                    [0.0], method="LSODA", rtol=1e-10, atol=1e-14)
    z = sol.y[0, -1]
    force = fr.lugre_force(z, fr.lugre_rate(z, v, SIGMA0, g), v, SIGMA0, SIGMA1, SIGMA2)
    assert force == pytest.approx(g + SIGMA2 * v, rel=1e-6)


def test_lugre_presliding_is_a_spring_of_stiffness_sigma0():
    """A small displacement x from rest (|x| << F_c / sigma0) is resisted like a spring sigma0 x;
    the first correction is -sigma0 x / (2 g): 5e-5 at x = 1 nm."""
    amplitude, period = 1e-9, 1.0  # far below F_c / sigma0 = 10 um

    def rhs(t, z):
        v = amplitude * 2 * math.pi / period * math.cos(2 * math.pi * t / period)
        return [fr.lugre_rate(z[0], v, SIGMA0, fr.lugre_g(v, F_C, F_S, V_S))]

    sol = solve_ivp(rhs, (0, period / 4), [0.0], rtol=1e-10, atol=1e-18)
    assert SIGMA0 * sol.y[0, -1] / amplitude == pytest.approx(SIGMA0, rel=1e-3)


def test_iwan_element_dissipates_the_masing_loop():
    """Cycling x = a sin wt with a > F_cr / k1: the loop's area is 4 F_cr (a - F_cr / k1). The
    element steps as the integrator carries it: its rates over each increment of x, then the
    return map."""
    k1, k2, f_cr, a = 1e4, 2e3, 5.0, 2e-3
    x = a * np.sin(np.linspace(0, 4 * math.pi, 40001))
    travel, stretch, forces = 0.0, 0.0, []
    for xi in x:
        _, travel_rate, stretch_rate = fr.iwan_bilinear(travel, stretch, xi - travel, k1, k2, f_cr)
        travel, stretch = travel + travel_rate, fr.iwan_return_map(stretch + stretch_rate, k1, f_cr)
        forces.append(fr.iwan_bilinear(travel, stretch, 0.0, k1, k2, f_cr)[0])
    forces = np.array(forces)
    half = x.size // 2  # second cycle (the first starts from the virgin state)
    work = np.trapezoid(forces[half:], x[half:])
    assert work == pytest.approx(4 * f_cr * (a - f_cr / k1), rel=1e-3)


def test_stribeck_holds_the_kinetic_coefficient_beyond_its_fitted_range():
    """Beyond v_m the polynomial would rise as v^3 (back to mu_s at sqrt(3) v_m, then without
    bound); the law holds mu_m there, continuous with zero slope at v_m."""
    mu_s, mu_m, v_m = 0.15, 0.10, 0.05
    assert fr.stribeck_polynomial(1e3 * v_m, mu_s, mu_m, v_m) == mu_m
    assert fr.stribeck_polynomial(-math.sqrt(3) * v_m, mu_s, mu_m, v_m) == mu_m
    h = 1e-7
    below = fr.stribeck_polynomial(v_m - h, mu_s, mu_m, v_m)
    assert below == pytest.approx(mu_m, abs=1e-12)                   # continuous
    assert (mu_m - below) / h == pytest.approx(0.0, abs=1e-5)        # zero slope from below
    speeds = np.linspace(0.0, 10 * v_m, 2001)
    assert max(fr.stribeck_polynomial(v, mu_s, mu_m, v_m) for v in speeds) <= mu_s


@pytest.mark.parametrize("alpha", [0.5, 1.0, 2.0])
def test_dahl_beyond_the_coulomb_force_is_finite_and_pulls_back(alpha):
    """|F| > F_c (a normal force that dropped): the rate is finite for every alpha and drives F
    back towards F_c; alpha = 1 is the linear form exactly."""
    sigma, f_c, v = 2e4, 3.0, 0.01
    for force in (1.5 * f_c, -1.5 * f_c):
        rate = fr.dahl_rate(force, v, sigma, f_c, alpha)
        assert math.isfinite(rate)
        assert (rate < 0) == (force > f_c)   # above F_c it falls; far below -F_c it rises
    assert fr.dahl_rate(1.5 * f_c, v, sigma, f_c, 1.0) == pytest.approx(sigma * (1 - 1.5) * v)
