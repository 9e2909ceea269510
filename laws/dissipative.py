"""Dissipative normal laws: the elastic force with a hysteresis (damping) term.

Hunt-Crossley type: F = F_el(d) (1 + chi d'/v0), d' the approach rate, v0 the impact speed
(the approach rate at first contact), chi a function of the coefficient of restitution e;
equivalently a damping eta = chi K / v0 on F_el = K d^n ([Cao2013] eqs. 4-8). The functions
named after their authors return chi(e). None of them reproduces its target e exactly:
`restitution` measures the effective e of any force law by integrating one impact.
"""

import math
from typing import NamedTuple

import numpy as np

from pinbore.core.cpp import laws as _core
from pinbore.laws.elastic import warn_once


def _check(e: float) -> None:
    if not 0 < e <= 1:
        raise ValueError(f"coefficient of restitution e = {e} must be in (0, 1]")


def hunt_crossley(e):
    """Hunt & Crossley 1975 [HuntCrossley1975]: chi = 3 (1 - e) / 2."""
    _check(e)
    return 1.5 * (1 - e)


def lankarani_nikravesh(e):
    """Lankarani & Nikravesh 1990 [LankaraniNikravesh1990]: chi = 3 (1 - e^2) / 4 ([Cao2013] eq. 7; derived for e near 1)."""
    _check(e)
    if e < 0.7:
        warn_once("lankarani_nikravesh", f"e = {e} is far from 1, where the law was derived")
    return 0.75 * (1 - e**2)


def lee_wang(e):
    """Lee & Wang 1983 [LeeWang1983]: chi = 3 (1 - e) / 4."""
    _check(e)
    return 0.75 * (1 - e)


def herbert_mcwhannell(e):
    """Herbert & McWhannell 1977 [HerbertMcWhannell1977]: chi = 6 (1 - e) / ((2e - 1)^2 + 3)."""
    _check(e)
    return 6 * (1 - e) / ((2 * e - 1) ** 2 + 3)


def zhiying_qishao(e):
    """Zhiying & Qishao 2006 [ZhiyingQishao2006] ([Cao2013] eq. 8): chi = 3 (1 - e^2) exp(2 (1 - e)) / 4."""
    _check(e)
    return 0.75 * (1 - e**2) * math.exp(2 * (1 - e))


def gonthier(e):
    """Gonthier et al. 2004 [Gonthier2004]: chi = (1 - e^2) / e."""
    _check(e)
    return (1 - e**2) / e


def flores(e):
    """Flores et al. 2011 [FloresMachado2011]: chi = 8 (1 - e) / (5 e)."""
    _check(e)
    return 1.6 * (1 - e) / e


def hu_guo(e):
    """Hu & Guo 2015 [HuGuo2015]: chi = 3 (1 - e) / (2 e)."""
    _check(e)
    return 1.5 * (1 - e) / e


HYSTERESIS = {f.__name__: f for f in (hunt_crossley, lankarani_nikravesh, lee_wang,
                                       herbert_mcwhannell, zhiying_qishao, gonthier, flores,
                                       hu_guo)}


# F = max(F_el (1 + chi d' / v0), 0): the Hunt-Crossley family (N, or N/m with F_el per
# length), never pulling (the bracket turns negative when the bodies separate faster than
# v0 / chi). The normal force of the multibody engine's continuous contact: the compiled
# core's (cpp/mechanism/laws.h), the very function the engine calls.
hysteresis_force = _core.hysteresis_force


def kelvin_voigt(d, rate, stiffness, damping):
    """Kelvin-Voigt ([Cao2013] eq. 2): F = K d + D d' (linear spring and dashpot; may pull)."""
    return stiffness * np.asarray(d, float) + damping * np.asarray(rate, float)


def kelvin_voigt_damping(e, stiffness, mass):
    """D for a target e, separation at d = 0: a damped linear oscillator rebounds with
    e = exp(-pi z / sqrt(1 - z^2)), so z = -ln e / sqrt(pi^2 + ln^2 e) and D = 2 z sqrt(K m)."""
    _check(e)
    z = -math.log(e) / math.hypot(math.pi, math.log(e))
    return 2 * z * math.sqrt(stiffness * mass)


def yigit(d, rate, stiffness, exponent, coefficient):
    """Yigit, Ulsoy & Scott 1990 [Yigit1990] ([Cao2013] eq. 9): F = K d^n + 0.75 C K d d', n >= 1."""
    d = np.asarray(d, float)
    return stiffness * d**exponent + 0.75 * coefficient * stiffness * d * np.asarray(rate, float)


def yigit_coefficient(e, stiffness, exponent, mass, speed):
    """C of `yigit` for a target e at impact speed v0, by the energy balance of Lankarani and
    Nikravesh (ours, first order in 1 - e): the damping term dissipates
    2 * 0.75 C K int_0^dm d v(d) dd = 1.5 C K v0 dm^2 I_n, with v = v0 sqrt(1 - (d/dm)^(n+1)),
    I_n = int_0^1 s sqrt(1 - s^(n+1)) ds, dm the elastic maximum approach; equal to
    m v0^2 (1 - e^2) / 2."""
    _check(e)
    n = exponent
    dm = ((n + 1) * mass * speed**2 / (2 * stiffness)) ** (1 / (n + 1))
    s = np.linspace(0, 1, 20001)
    integral = np.trapezoid(s * np.sqrt(np.clip(1 - s ** (n + 1), 0, None)), s)
    return mass * speed * (1 - e**2) / (3 * stiffness * dm**2 * integral)


class Impact(NamedTuple):
    """One impact of a mass on a force law (`impact`)."""

    restitution: float    # e = |d'_out| / v0
    duration: float       # s, from first contact to separation (d = 0)
    max_approach: float   # m, the largest d


def impact(force, mass, speed) -> Impact:
    """One impact of a mass m meeting a force law F(d, d') at speed v0: m d'' = -F, d(0) = 0,
    d'(0) = v0, until d returns to 0 (DOP853, rtol 1e-11). The effective restitution
    e = |d'_out| / v0, the contact duration and the largest approach (at d' = 0)."""
    from scipy.integrate import solve_ivp   # noqa: PLC0415 (a scene validates without SciPy)

    def rhs(_, y):
        return [y[1], -force(y[0], y[1]) / mass]

    def leaves(_, y):
        return y[0]
    leaves.terminal, leaves.direction = True, -1

    def turns(_, y):
        return y[1]
    turns.direction = -1

    # time scale: the elastic contact duration is a few (m / K)^(1/2); integrate far enough
    span = 1.0
    while True:
        sol = solve_ivp(rhs, (0, span), [0.0, speed], method="DOP853", rtol=1e-11, atol=1e-15,
                        events=(leaves, turns), dense_output=False, first_step=span * 1e-9)
        if sol.t_events[0].size:
            deepest = float(sol.y_events[1][0][0]) if sol.t_events[1].size else float(sol.y.max())
            return Impact(abs(sol.y_events[0][0][1]) / speed, float(sol.t_events[0][0]), deepest)
        span *= 10


def restitution(force, mass, speed):
    """Effective coefficient of restitution of a force law F(d, d') in one impact: a mass m
    meets the contact at speed v0 and leaves it when d returns to 0; e = |d'_out| / v0
    (`impact`)."""
    return impact(force, mass, speed).restitution



def hysteresis_for_restitution(e):
    """chi of the Hunt-Crossley force F = F_el(d) (1 + chi d'/v0) [HuntCrossley1975] that
    rebounds with exactly e, for any elastic law F_el (ours). With u = d'/v0 and the elastic
    work W = int F_el dd / (m v0^2), m d'' = -F gives u du = -(1 + chi u) dW: F_el drops out.
    Loading (u: 1 -> 0) and unloading (u: 0 -> -e) span the same W, so
    int_0^1 u / (1 + chi u) du = int_0^e w / (1 - chi w) dw, i.e.
    chi (1 + e) = ln((1 + chi) / (1 - chi e)), whose one root in (0, 1/e) is found by
    bisection to 1e-14 relative (chi e < 1: the force never falls to zero before
    separation). Near e = 1 it gives 1 - e^2 = 4 chi / 3 (Lankarani-Nikravesh's first
    order)."""
    if not 0.0 < e <= 1.0:
        raise ValueError("coefficient of restitution e must be in (0, 1]")
    if e == 1.0:
        return 0.0
    low, high = 0.0, 1.0 / e   # g(chi) = ln(1 + chi) - ln(1 - chi e) - chi (1 + e): < 0, then > 0
    chi = 0.5 * high
    for _ in range(200):
        chi = 0.5 * (low + high)
        if math.log1p(chi) - math.log1p(-chi * e) - chi * (1.0 + e) < 0.0:
            low = chi
        else:
            high = chi
        if high - low <= 1e-14 * high:
            break
    return chi


def restitution_of_speed(speed, coefficients, low, high):
    """e(v0) = sum_k a_k x^k, x = ln(v0 / 1 m/s), coefficients (a_0, a_1, ...): the
    restitution of FE impacts fitted against the impact speed (ours;
    calibration.restitution). Outside [low, high] (m/s), where no FE impact was run, e is
    held at its value at the nearer end (the caller warns); e is kept in [1e-6, 1]."""
    x = math.log(min(max(speed, low), high))
    e = 0.0
    for k in range(len(coefficients) - 1, -1, -1):
        e = e * x + coefficients[k]
    return min(max(e, 1e-6), 1.0)
