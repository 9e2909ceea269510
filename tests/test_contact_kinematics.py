"""The contact building blocks against closed forms: gaps of circles, segment search across
the angle seam, a projection held on its patch, tributary lengths, the contact edge of a
Hertz pressure profile."""

import math

import numpy as np
import pytest

from pinbore.fem.contact import BoreSurface, bracket, kinematics, tributary_lengths
from pinbore.fem.post import angle_from, half_angle

R_BORE, R_PIN = 10.0e-3, 9.9e-3


def circle_segments(n=720, displacement=None):
    angles = np.sort(np.remainder(np.linspace(0, 2 * np.pi, n, endpoint=False) + 0.1, 2 * np.pi) - np.pi)
    return BoreSurface(R_BORE, angles, np.zeros((n, 2)) if displacement is None else displacement)


def test_gap_of_a_translated_pin_is_exact():
    """Undeformed bore, pin translated by t: g = R_bore - |X + t| exactly (no faceting)."""
    theta = np.linspace(-np.pi, np.pi, 97)
    t = np.array([3e-5, -8e-5])
    x = R_PIN * np.stack([np.cos(theta), np.sin(theta)], 1) + t
    bore = circle_segments(n=60)  # coarse: a chord would sit 1.4e-5 m inside the circle
    kin = kinematics(x, bore)
    np.testing.assert_allclose(kin.gap, R_BORE - np.linalg.norm(x, axis=1), atol=1e-15)
    np.testing.assert_allclose(kin.normal, x / np.linalg.norm(x, axis=1)[:, None], atol=1e-12)
    np.testing.assert_allclose(kin.rho, R_BORE, rtol=1e-12)


def test_gap_is_invariant_under_a_common_translation():
    """Translating pin and bore together changes no gap: momentum is conserved. (A smooth
    bore displacement: at the kinks of a rough one the closest point is ambiguous.)"""
    n = 360
    angles = circle_segments(n).angles
    bore = circle_segments(n, 1e-6 * np.stack([np.cos(3 * angles), np.sin(2 * angles)], 1))
    x = R_PIN * np.stack([np.cos(np.linspace(-3, 3, 50)), np.sin(np.linspace(-3, 3, 50))], 1)
    g0 = kinematics(x, bore).gap
    shift = np.array([2e-5, 1e-5])
    moved = BoreSurface(bore.radius, bore.angles, bore.displacement + shift)
    g1 = kinematics(x + shift, moved).gap
    np.testing.assert_allclose(g1, g0, atol=1e-15)


def test_uniform_radial_expansion_of_the_bore_opens_the_gap_by_as_much():
    """Up to the linear interpolation of the displacement along a segment (dTheta^2 / 8)."""
    n = 200
    bore = circle_segments(n)
    e_r = np.stack([np.cos(bore.angles), np.sin(bore.angles)], 1)
    expanded = BoreSurface(R_BORE, bore.angles, 2e-6 * e_r)
    x = R_PIN * np.stack([np.cos(np.linspace(-3, 3, 31)), np.sin(np.linspace(-3, 3, 31))], 1)
    g0 = kinematics(x, bore).gap
    g1 = kinematics(x, expanded).gap
    np.testing.assert_allclose(g1 - g0, 2e-6, rtol=(2 * np.pi / n) ** 2 / 8)


def test_bracket_across_the_angle_seam():
    angles = np.array([-3.0, -1.0, 1.0, 3.0])
    k, xi = bracket(np.array([3.1, -3.1, 0.0, -3.0]), angles)
    gap = 2 * np.pi - 6.0
    np.testing.assert_array_equal(k, [3, 3, 1, 0])
    np.testing.assert_allclose(xi, [0.1 / gap, (gap - 0.1 + 1e-12) / gap, 0.5, 0.0], atol=1e-9)


def test_tributary_lengths_sum_to_the_perimeter():
    theta = np.sort(np.random.default_rng(0).uniform(-np.pi, np.pi, 300))
    points = np.stack([np.cos(theta), np.sin(theta)], 1)
    perimeter = np.linalg.norm(np.roll(points, -1, 0) - points, axis=1).sum()
    assert tributary_lengths(points).sum() == pytest.approx(perimeter, rel=1e-13)


@pytest.mark.parametrize("spacing_deg", [0.5, 0.1])
def test_half_angle_of_a_sampled_hertz_profile(spacing_deg):
    """p = p0 sqrt(1 - (alpha/eps)^2) sampled at nodes: the edge is found within a tenth of
    the node spacing, whatever the load direction (here across the seam at 180 deg)."""
    eps = math.radians(23.37)
    alpha = np.radians(np.arange(-90, 90, spacing_deg) + 0.013)
    p = 1e8 * np.sqrt(np.clip(1 - (alpha / eps) ** 2, 0, None))
    theta = np.remainder(alpha + np.pi + np.pi, 2 * np.pi) - np.pi   # load at 180 deg
    found = half_angle(angle_from(180.0, theta), p)
    assert abs(found - eps) < 0.1 * math.radians(spacing_deg)


def test_a_held_projection_keeps_its_patch_within_the_band():
    """A pin node whose closest point lies 2 % of a patch past the end of patch k, projected
    with k held: it stays on k, its surface coordinate 1.02, and its gap is the circle's
    exact R_bore - |x| (the reference patch is the arc, extended); 20 % past the end (beyond
    the band) it moves on to patch k + 1 at 0.2; unheld it goes to k + 1 at 0.02."""
    from pinbore.fem.contact import HELD_BAND

    bore = circle_segments(n=60)
    k = 20
    width = bore.widths[k]
    for past, patch, zeta in ((0.02, k, 1.02), (0.2, k + 1, 0.2)):
        angle = bore.angles[k + 1] + past * width
        x = np.array([[R_PIN * math.cos(angle), R_PIN * math.sin(angle)]])
        held = kinematics(x, bore, held=np.array([k]), band=HELD_BAND)
        assert held.projection.k[0] == patch
        assert held.projection.zeta[0, 0] == pytest.approx(zeta, abs=1e-9)
        assert held.gap[0] == pytest.approx(R_BORE - R_PIN, abs=1e-15)
    angle = bore.angles[k + 1] + 0.02 * width
    free = kinematics(np.array([[R_PIN * math.cos(angle), R_PIN * math.sin(angle)]]), bore)
    assert free.projection.k[0] == k + 1 and free.projection.zeta[0, 0] == pytest.approx(0.02, abs=1e-9)
