"""Quantities read off a converged state: contact half-angle, pressure profile."""

import numpy as np


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
