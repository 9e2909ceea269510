"""The sliced cylindrical-joint law: force and tilting moment of a finite pin in its bore.

A pin sits in a bore of length L (m, the lug's thickness) spanning 0 <= z <= L. The hub
approaches by delta (m) along the load and tilts by theta (rad, small) about the axis normal
to the load and to the pin's axis, through the bore's mid-plane centre z_mid = L/2; positive
theta turns the pin's end z = L towards the load. The local approach is

    delta(z) = delta + theta (z - z_mid) - r(z)   (m),

r(z) the bore's edge relief (pinbore.laws.relief; none when its length or depth is 0). The
bore is cut into n equal slices, midpoints z_i = (i + 1/2) L/n, and each slice is a plane
section carrying a per-length law f(delta_i) (N/m; 0 for delta_i <= 0) of its own approach,
independently of its neighbours: the elastic-foundation idealisation [Johnson1985], here
applied along the axis with a plane-strain law per slice (e.g. the improved elastic-foundation
law of [Liu2007] or Johnson's line contact, pinbore.laws.elastic). The slicing along the axis
is this module's own construction (no source for it is cited); the coupling of neighbouring
slices through the bodies, which it leaves out, shows at the ends, where a fitted end length
stands in for it. The sums are the midpoint rule of the integrals of f(delta(z)) and of
f(delta(z)) (z - z_mid) over [0, L], with weights w_i:

    F   = sum_i f(delta_i) w_i                 (N, the force the hub needs, along the load)
    M   = sum_i f(delta_i) (z_i - z_mid) w_i   (N m, about the across axis)
    w_i = L/n + e [i = 0] + e [i = n - 1]      (m),

e = `end_length` (m, may be negative): each end adds e metres of the per-length law at its
end slice's approach, moment arm that of the end slice (with n = 1 the one slice gets both).
F and M are the generalised forces conjugate to delta and theta (the virtual work of the
slices is sum_i f_i w_i d(delta_i) = F d(delta) + M d(theta)), so M > 0 for theta > 0 without
relief. The resultant acts at z_F = z_mid + M/F (NaN when F = 0); the contact length is the
sum of the widths L/n of the slices with delta_i > 0.

The per-length law enters as a table of ln f on a uniform grid of ln delta
(pinbore.laws.tables: exact for a power law, NaN beyond the table, so a slice beyond the
law's range makes F, M and z_F NaN rather than a silent number). The functions are compiled
(numba) so the multibody kernel can call them in its right-hand side.
"""

import math

import numba
import numpy as np

from pinbore.core.compiled import follow_compiled_in
from pinbore.laws import relief, tables


@numba.njit(cache=True)
def slice_geometry(i, length, slices, end_length):
    """Slice i of `slices` over a bore of `length` (m): its offset z_i - L/2 from the
    mid-plane, its width L/n and its weight w_i = L/n + end_length at each end slice (m)."""
    width = length / slices
    offset = (i + 0.5 - 0.5 * slices) * width          # antisymmetric about the mid-plane
    return offset, width, width + end_length * ((i == 0) + (i == slices - 1))


@numba.njit(cache=True)
def slice_state(i, delta, theta, length, slices, grid_log0, grid_step, table, relief_length,
                relief_depth):
    """Slice i of `slices`: its offset z_i - z_mid (m), approach delta_i (m) and per-length
    force f_i (N/m; 0 when delta_i <= 0) (the module docstring has the formulas)."""
    offset = slice_geometry(i, length, slices, 0.0)[0]
    approach = delta + theta * offset
    if relief_length > 0.0 and relief_depth > 0.0:
        approach -= relief.relief_at(0.5 * length + offset, 0.0, length, relief_length,
                                     relief_depth)[0]
    force = tables.table_force(approach, grid_log0, grid_step, table) if approach > 0.0 else 0.0
    return offset, approach, force


@numba.njit(cache=True)
def sliced(delta, theta, length, slices, grid_log0, grid_step, table, relief_length, relief_depth,
           end_length):
    """(F (N), M (N m), z_F (m), contact length (m)) of a pin approached by delta (m) and
    tilted by theta (rad) in a bore of `length` (m) cut into `slices` slices, the per-length
    law f (N/m) given by its table (grid_log0, grid_step, table = ln f: pinbore.laws.tables),
    the bore's edge relief over `relief_length` to `relief_depth` (m; 0 for none), and
    `end_length` (m) of per-length law added at each end:

        F = sum_i f(delta_i) w_i,   M = sum_i f(delta_i) (z_i - L/2) w_i,
        w_i = L/n + end_length at i = 0 and at i = n - 1,   z_F = L/2 + M/F,

    delta_i = delta + theta (z_i - L/2) - r(z_i) (module docstring; [Johnson1985] for the
    elastic-foundation idealisation). z_F is NaN when F = 0; F, M, z_F are NaN when a slice
    is beyond the table."""
    force = moment = contact = 0.0
    for i in range(slices):
        offset, approach, f = slice_state(i, delta, theta, length, slices, grid_log0, grid_step,
                                          table, relief_length, relief_depth)
        if approach <= 0.0:
            continue
        _, width, weight = slice_geometry(i, length, slices, end_length)
        force += f * weight
        moment += f * offset * weight
        contact += width
    resultant = 0.5 * length + moment / force if force != 0.0 else math.nan
    return force, moment, resultant, contact


@numba.njit(cache=True)
def sliced_profile(delta, theta, length, slices, grid_log0, grid_step, table, relief_length,
                   relief_depth):
    """The slices of `sliced` (same arguments but the end length): arrays of their midpoints
    z_i (m), approaches delta_i (m) and per-length forces f_i (N/m), the pressure along the
    pin as the law sees it."""
    z, approach, force = np.empty(slices), np.empty(slices), np.empty(slices)
    for i in range(slices):
        offset, approach[i], force[i] = slice_state(i, delta, theta, length, slices, grid_log0,
                                                    grid_step, table, relief_length, relief_depth)
        z[i] = 0.5 * length + offset
    return z, approach, force


def slices_for_force(delta, theta, length, grid_log0, grid_step, table, relief_length=0.0,
                     relief_depth=0.0, end_length=0.0, tolerance=0.01, start=4, most=1 << 16,
                     resolved=8):
    """The number of slices n (start 2^k) that gives F within `tolerance` (relative) of its
    limit n -> infinity: doubling n from `start` until F changes by less than tolerance / 2.

    Richardson: if F_n = F + C h^p (h = L/n, p >= 1), then F_n - F = (F_n - F_2n) 2^p/(2^p - 1),
    at most twice the change, so a change below tolerance / 2 bounds the error of F_n by the
    tolerance for any order p >= 1 (the midpoint rule gives p = 2, tests/test_sliced.py).
    The error of the slice that holds a contact edge does not follow C h^p smoothly: for a
    linear law it is -k |theta| eps^2 / 2, eps the distance of the edge to the nearest slice
    boundary, which can stay the same over several doublings and fake a converged F. So where
    the contact stops inside the bore, n must also hold at least `resolved` slices in contact:
    the edge slice's relative error is then at most (1 / (2 resolved))^2 (0.4 % for 8) for a
    linear law. No slice in contact up to `most` slices: `start` (F = 0 to that resolution).
    Raises ValueError if F is NaN (beyond the law's table) or does not settle by `most`.
    """
    def run(n):
        return sliced(delta, theta, length, n, grid_log0, grid_step, table, relief_length,
                      relief_depth, end_length)

    n = start
    coarse = run(n)
    while 2 * n <= most:
        fine = run(2 * n)
        if math.isnan(coarse[0]) or math.isnan(fine[0]):
            raise ValueError("the sliced force is NaN: an approach beyond the law's table")
        contact_slices = round(coarse[3] / (length / n))
        edge_resolved = contact_slices == n or contact_slices >= resolved
        if fine[0] == 0.0 and coarse[0] == 0.0:
            n, coarse = 2 * n, fine
            continue
        if abs(fine[0] - coarse[0]) < 0.5 * tolerance * abs(fine[0]) and edge_resolved:
            return n
        n, coarse = 2 * n, fine
    if coarse[0] == 0.0:
        return start
    raise ValueError(f"the sliced force does not settle within {tolerance:g} by {most} slices")


# numba's cache follows only this file: the law compiles in the table lookup and the relief.
COMPILED_IN = (tables.__file__, relief.__file__)
follow_compiled_in(globals(), COMPILED_IN)
