"""The depth Archard's law wears into the bore and into the pin over a joint's history: at the
angle theta of a surface's own frame,

    h(theta) = integral k p((theta - theta_c(t)) R / R_bore; F(t) / L) |v_s(t)| dt,

p the FE pressure under the load per unit length F / L at the angle from the contact's
direction theta_c (in that surface's frame) about the bore's centre (a point of the contact
at the arc length R (theta - theta_c) from its middle on a surface of radius R), v_s the
sliding speed, k the surface's wear coefficient [Archard1953] (laws.wear). The time integral
is the trapezoidal rule over the recorded steps with each step's pressure swept over the arc
the contact turns to its neighbours: half an interval at step k deposits the mean of p_k over
theta_c moving uniformly from theta_c,k to theta_c,k+1,

    (dt / 2) k |v_k| (P_k(u_k) - P_k(u_k+1)) / (u_k - u_k+1),   u = (theta - theta_c) R / R_bore,

P_k the integral of p_k over the angle (exact, to the FE table's spacing, for a contact
turning uniformly under a constant load; toward a neighbour out of contact the contact
stands). The recorded steps sample a contact that slides, median 2.8 degrees apart on the Flores
joint, where the worn profile is read every half degree: taken at the steps alone, p would lay
ripples of that spacing into the profile. Both surfaces lose the same area per unit k. One-way:
the geometry the pressure was computed on is kept (a cycle's wear is a fraction of a micrometre
against a clearance of hundreds)."""

import math

import numpy as np

from pinbore.laws.wear import archard_depth_rate

SWEPT = 1e-9   # rad: a contact turning less over an interval stands (its pressure at its angle)


def angles(points: int) -> np.ndarray:
    """`points` angles (rad) evenly around a surface, from -pi."""
    return -math.pi + 2 * math.pi * np.arange(points) / points


def worn_depth(table, time, force_per_length, contact_angle, sliding_speed, coefficient: float,
               at: np.ndarray, radius: float, tables=None) -> np.ndarray:
    """h at the angles `at` (m, evenly spaced from -pi: `angles`) of a surface of `radius` (m)
    after the history (arrays per recorded step: s, N/m, rad in the surface's frame, m/s) on
    the pressure table (wear.pressure.PressureTable). A step touches only the angles within
    the table's reach of its contact (the arc it sweeps added). `tables`: a table per step
    for this surface (wear.pressure.worn_tables) in place of `table`."""
    scale = radius / table.bore_radius
    depth = np.zeros(at.size)
    spacing = 2 * math.pi / at.size
    for k in range(time.size):
        f, v = force_per_length[k], sliding_speed[k]
        if f <= 0 or v == 0:
            continue
        mine = table if tables is None else tables[k]
        sides = []
        for j in (k - 1, k + 1):   # the half intervals on either side of step k
            if not 0 <= j < time.size or time[j] == time[k]:
                continue
            # toward a neighbour out of contact (its direction the offset's) the contact stands
            turn = 0.0 if force_per_length[j] <= 0 else \
                scale * (np.mod(contact_angle[j] - contact_angle[k] + math.pi, 2 * math.pi) - math.pi)
            sides.append((j, turn))
        if not sides:
            continue
        reach = (mine.reach + max(abs(turn) for _, turn in sides)) / scale
        centre = int(round((contact_angle[k] + math.pi) / spacing))
        count = min(2 * int(reach / spacing) + 5, at.size)
        window = (centre - count // 2 + np.arange(count)) % at.size
        start = scale * (np.mod(at[window] - contact_angle[k] + math.pi, 2 * math.pi) - math.pi)
        integral = None
        for j, turn in sides:
            if abs(turn) < SWEPT:
                pressure = np.interp(start, mine.angles, mine.at(f), left=0.0, right=0.0)
            else:
                integral = mine.integral_at(f) if integral is None else integral
                swept = (np.interp(start, mine.angles, integral, left=0.0, right=integral[-1])
                         - np.interp(start - turn, mine.angles, integral, left=0.0, right=integral[-1]))
                pressure = swept / turn
            depth[window] += 0.5 * abs(time[j] - time[k]) * archard_depth_rate(pressure, v, coefficient)
    return depth


def volume_per_length(depth: np.ndarray, radius: float) -> float:
    """The worn area of a section, integral h R dtheta over the evenly spaced angles (m^2:
    the volume per unit length of the pin, m^3/m)."""
    return float(np.sum(depth) * radius * 2 * math.pi / depth.size)
