"""The sliced cylindrical-joint law: force and tilting moment of a finite pin in its bore.

A pin sits in a bore of length L (m, the lug's thickness) spanning 0 <= z <= L. The hub
approaches by delta (m) along the load and tilts by theta (rad, small) about the axis normal
to the load and to the pin's axis, through the bore's mid-plane centre z_mid = L/2; positive
theta turns the pin's end z = L towards the load.

The bore is cut into n equal slices, midpoints z_i = (i + 1/2) L/n, each a plane section
carrying a per-length law of its own approach: the elastic-foundation idealisation
[Johnson1985], here applied along the axis with a plane-strain law per slice (e.g. the
improved elastic-foundation law of [Liu2007] or Johnson's line contact,
pinbore.laws.elastic). The slicing along the axis, and the split of the section law below,
are this module's own construction (no source for them is cited).

Shared bulk compliance. A plane-section law f(delta) (N/m) holds two compliances in series:
the contact region's and the far field's, the housing around the bore carrying the load out
to its support. In a finite pin the far field is a plate of thickness L that sees only the
resultant F of the slices (Saint-Venant): it moves the bore as a whole, uniformly along z.
So the section law is split, for a bulk compliance c_b (m^2/N) per unit length,

    delta = u + c_b f_loc(u)      (f(delta) = f_loc(u): the local law f_loc of the slices),

pinbore.laws.tables.split_compliance, and the slices see the hub's approach less the bore's
uniform displacement c_b F / L:

    delta_i = delta - c_b F / L + theta (z_i - z_mid) - r(z_i)   (m),
    F   = a sum_i f_loc(delta_i) w_i                 (N, the force the hub needs, along the load)
    M   = a sum_i f_loc(delta_i) (z_i - z_mid) w_i   (N m, about the across axis)
    w_i = L/n + e [i = 0] + e [i = n - 1]            (m),

r(z) the bore's edge relief (pinbore.laws.relief; none when its length or depth is 0), a a
stiffness factor and e = `end_length` (m, may be negative): each end adds e metres of the law
at its end slice's approach, moment arm that of the end slice (with n = 1 the one slice gets
both). F is implicit in delta_i. With c_b = 0 the slices are independent. A straight pin
(theta = 0, no relief) with a = 1, e = 0 carries f(delta) L for any c_b: the split
leaves the plane-section law whole where the load is uniform, so the long-pin limit is the 2D law. Under
tilt the far field takes the resultant's part of the approach only; the tilt goes into the
local compression, so a tilted pin carries more moment, nearer its loaded end, than
independent slices of the whole section law give (what the 3D FE shows: calibration/sliced.py).

The section in 2D. In space the journal's axis meets slice i's plane at P_i = A + z'_i B
(m, in the bore's section, from the bore's axis: A the eccentricity at the mid-plane, B the
tilt's lean per metre), and the far field moves the bore by a vector d. The slice's approach
is delta_i = |P_i - d| - c - r(z_i) (c the radial clearance) along n_i = (P_i - d)/|P_i - d|,
and the slices' resultant F = a sum_i f_loc(delta_i) w_i n_i moves the bore by
d = c_b F / L. The root of g(d) = d - c_b F(d) / L is the minimum of

    Psi(d) = |d|^2 / 2 + (c_b / L) a sum_i w_i U(delta_i(d)),   U' = f_loc,

strongly convex (U is convex and increasing, delta_i convex in d), so it is unique,
|d| <= c_b |F(0)| / L, and Newton's method on g, whose Jacobian I + (c_b / L) K is symmetric
positive definite, K = a sum_i w_i [f'_i n_i n_i^T + f_i / |P_i - d| (I - n_i n_i^T)], finds it
when every step that overshoots the minimum along its direction is cut back to it
(bore_displacement). The plane law above is the in-plane case: P_i = (delta + theta z'_i) along
x, c = 0, the approach taken along x (no curvature term), d = (c_b F / L, 0), so
x = delta - d_x; the spatial mechanisms (the compiled core, cpp/mechanism/laws.h) take the general one.
This section geometry and its potential are the project's own construction.

F and M are the generalised forces conjugate to delta and theta (the virtual work of the
slices is sum_i f_i w_i d(delta_i) = F d(delta) + M d(theta) plus the far field's, whose
uniform displacement does no work against a moment), so M > 0 for theta > 0 without relief.
The resultant acts at z_F = z_mid + M/F (NaN when F = 0); the contact length is the sum of
the widths L/n of the slices with delta_i > 0.

The local law enters as a table of ln f_loc on a uniform grid of ln u (pinbore.laws.tables:
exact for a power law, NaN beyond the table, so a slice beyond the law's range makes F, M
and z_F NaN rather than a silent number). The functions are the compiled core's, the ones the
multibody engine calls in its right-hand side.
"""

import math

from pinbore.core.cpp import laws as _core

# the law's functions, the compiled core's (cpp/mechanism/laws.h), which the multibody
# engine's sliced journal evaluates:
# - slice_geometry(i, length, slices, end_length): slice i's offset z_i - L/2 from the
#   mid-plane, its width L/n and its weight w_i = L/n + end_length at each end slice (m);
# - slice_contact(i, dx, dy, ax, ay, bx, by, clearance, planar, length, slices, grid_log0,
#   grid_step, table, relief_length, relief_depth): slice i in the bore's section ("The
#   section in 2D"), the journal's axis at P_i = (ax, ay) + z'_i (bx, by) against the bore
#   moved by (dx, dy); planar: the in-plane case, approach P_ix - dx - clearance - r(z_i)
#   along x, else |P_i - d| - clearance - r(z_i) along n_i. (z'_i (m), approach (m), n_ix,
#   n_iy, the curvature 1/|P_i - d| (1/m; 0 in plane), f_i (N/m; 0 when open), df_i/d delta_i);
# - section_sums(dx, dy, ..., end_length, scale): (F_x, F_y (N), M_x, M_y (N m), the stiffness
#   -dF/dd (K_xx, K_xy, K_yy, N/m), contact length (m)), F = a sum_i f_i w_i n_i and
#   K = a sum_i w_i [f'_i n_i n_i^T + f_i / |P_i - d| (I - n_i n_i^T)];
# - bore_displacement(ax, ay, bx, by, clearance, planar, length, slices, ..., end_length,
#   scale, compliance): (d_x, d_y) the root of g(d) = d - compliance F(d) / L, Newton's method
#   with the Jacobian I + (compliance / L) K from d = 0, a step that overshoots the minimum of
#   Psi along its direction cut back by regula falsi (Illinois), to 1e-12 of the section's
#   size; (0, 0) without compliance or contact, NaN when F is NaN;
# - shared_approach(delta, theta, length, slices, ..., compliance): x = delta - compliance
#   F(x) / L, the in-plane case of bore_displacement;
# - sliced(delta, theta, length, slices, grid_log0, grid_step, table, relief_length,
#   relief_depth, end_length, scale, compliance): (F (N), M (N m), z_F (m), contact length
#   (m)) as the module docstring gives them, z_F NaN when F = 0, all NaN beyond the table;
# - sliced_profile(same arguments): arrays of the slices' midpoints z_i (m), approaches (m)
#   and per-length forces a f_loc(delta_i) (N/m).
slice_geometry = _core.slice_geometry
slice_contact = _core.slice_contact
section_sums = _core.section_sums
bore_displacement = _core.bore_displacement
shared_approach = _core.shared_approach
sliced = _core.sliced
sliced_profile = _core.sliced_profile


def slices_for_force(delta, theta, length, grid_log0, grid_step, table, relief_length=0.0,
                     relief_depth=0.0, end_length=0.0, scale=1.0, compliance=0.0, tolerance=0.01,
                     start=4, most=1 << 16, resolved=8):
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
                      relief_depth, end_length, scale, compliance)

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
