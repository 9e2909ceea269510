"""Quantities read off a converged state: contact half-angle, pressure profile, axial
contact length, axial position of the resultant."""

import numpy as np

from pinbore.fem.contact import axial_widths


def angle_from(direction_deg: float, theta: np.ndarray) -> np.ndarray:
    """Signed angle (rad) of polar angles theta from the load direction, in (-pi, pi]."""
    return np.remainder(theta - np.radians(direction_deg) + np.pi, 2 * np.pi) - np.pi


def contact_edge(alpha: np.ndarray, p: np.ndarray) -> float:
    """Where the pressure vanishes on one side: alpha >= 0 sorted ascending, p >= 0 at nodes.

    Near the edge of an elastic contact p ~ sqrt(edge - alpha) (Hertz, Persson), so p^2 is
    linear there: extrapolate p^2 through the last two loaded nodes to zero, and keep the
    result between the last loaded node and the first free one.
    """
    loaded = np.flatnonzero(p > 0)
    if loaded.size == 0:
        return 0.0
    j = loaded.max()
    if j + 1 >= alpha.size:
        return float(alpha[j])
    if j == 0 or p[j - 1] <= p[j]:
        return float(alpha[j])
    slope = (p[j - 1] ** 2 - p[j] ** 2) / (alpha[j] - alpha[j - 1])
    return float(np.clip(alpha[j] + p[j] ** 2 / slope, alpha[j], alpha[j + 1]))


def half_angle(alpha: np.ndarray, p: np.ndarray) -> float:
    """Contact half-angle (rad): the mean of the edges on either side of the load direction."""
    edges = []
    for side in (1, -1):
        on_side = side * alpha >= 0
        a, q = side * alpha[on_side], p[on_side]
        order = np.argsort(a)
        edges.append(contact_edge(a[order], q[order]))
    return 0.5 * (edges[0] + edges[1])


def contact_length(pressure: np.ndarray, levels: np.ndarray, copies: int = 1) -> float:
    """Axial length (m) of the pin in contact: the tributary lengths of the levels where any
    node presses (pressure as (levels, angles)), times `copies` (2: a half model)."""
    return copies * float(axial_widths(levels)[(pressure > 0).any(axis=1)].sum())


def resultant_z(force: float, moment: float, pivot_z: float) -> float:
    """Axial position (m) of the resultant of a force F along the load whose moment about the
    tilt axis through (0, 0, pivot_z) is M: the moment of F d at z is F (z - pivot_z) (the
    tilt axis is e_z x d), so z = pivot_z + M / F; NaN without force."""
    return pivot_z + moment / force if force > 0 else float("nan")


def pressure_moment(pressure, normal, weights, X, pivot, axis) -> float:
    """Moment (N m) of the contact pressure on the pin about the axis `axis` through `pivot`,
    taken with the sign of the hub's moment that balances it: sum w p (X - c) x nu . a over
    the pin nodes (reference positions X, tributary areas w, bore normals nu; the bore
    pushes the pin along -nu). Equals the hub's tilting moment of a frictionless contact,
    by the pin's equilibrium."""
    arm = np.asarray(X) - np.asarray(pivot)
    return float(np.sum((weights * pressure)[:, None] * np.cross(arm, normal) @ np.asarray(axis)))
