"""The depth Archard's law wears into the bore and into the pin over a joint's history: at the
angle theta of a surface's own frame,

    h(theta) = integral k p((theta - theta_c(t)) R / R_bore; F(t) / L) |v_s(t)| dt,

p the FE pressure under the load per unit length F / L at the angle from the contact's
direction theta_c (in that surface's frame) about the bore's centre (a point of the contact
at the arc length R (theta - theta_c) from its middle on a surface of radius R), v_s the
sliding speed, k the surface's wear coefficient [Archard1953] (laws.wear); the trapezoidal
rule over the recorded steps. Both surfaces lose the same area per unit k. One-way:
the geometry the pressure was computed on is kept (a cycle's wear is a fraction of a micrometre
against a clearance of hundreds)."""

import math

import numpy as np

from pinbore.laws.wear import archard_depth_rate


def angles(points: int) -> np.ndarray:
    """`points` angles (rad) evenly around a surface, from -pi."""
    return -math.pi + 2 * math.pi * np.arange(points) / points


def worn_depth(table, time, force_per_length, contact_angle, sliding_speed, coefficient: float,
               at: np.ndarray, radius: float) -> np.ndarray:
    """h at the angles `at` (m) of a surface of `radius` (m) after the history (arrays per
    recorded step: s, N/m, rad in the surface's frame, m/s) on the pressure table
    (wear.pressure.PressureTable)."""
    scale = radius / table.bore_radius
    weight = np.zeros(time.size)
    dt = np.diff(time)
    weight[:-1] += 0.5 * dt
    weight[1:] += 0.5 * dt
    depth = np.zeros(at.size)
    for w, f, theta, v in zip(weight, force_per_length, contact_angle, sliding_speed):
        if w <= 0 or f <= 0 or v == 0:
            continue
        relative = scale * (np.mod(at - theta + math.pi, 2 * math.pi) - math.pi)
        pressure = np.interp(relative, table.angles, table.at(f), left=0.0, right=0.0)
        depth += w * archard_depth_rate(pressure, v, coefficient)
    return depth


def volume_per_length(depth: np.ndarray, radius: float) -> float:
    """The worn area of a section, integral h R dtheta over the evenly spaced angles (m^2:
    the volume per unit length of the pin, m^3/m)."""
    return float(np.sum(depth) * radius * 2 * math.pi / depth.size)
