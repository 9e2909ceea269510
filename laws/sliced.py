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
and z_F NaN rather than a silent number). The functions are compiled (numba) so the
multibody kernel can call them in its right-hand side.
"""

import math

import numba
import numpy as np

from pinbore.core.compiled import follow_compiled_in
from pinbore.laws import relief, tables


@numba.njit(cache=True, _nrt=False)
def slice_geometry(i, length, slices, end_length):
    """Slice i of `slices` over a bore of `length` (m): its offset z_i - L/2 from the
    mid-plane, its width L/n and its weight w_i = L/n + end_length at each end slice (m)."""
    width = length / slices
    offset = (i + 0.5 - 0.5 * slices) * width          # antisymmetric about the mid-plane
    return offset, width, width + end_length * ((i == 0) + (i == slices - 1))


@numba.njit(cache=True, _nrt=False)
def slice_contact(i, dx, dy, ax, ay, bx, by, clearance, planar, length, slices, grid_log0,
                  grid_step, table, relief_length, relief_depth):
    """Slice i of `slices` in the bore's section (module docstring, "The section in 2D"): the
    journal's axis at P_i = (ax, ay) + z'_i (bx, by) (m) against the bore moved by (dx, dy)
    (m). planar: the section's in-plane case, approach P_ix - dx - clearance - r(z_i) along
    x; else the approach |P_i - d| - clearance - r(z_i) along n_i = (P_i - d) / |P_i - d|.
    Returns (z'_i = z_i - z_mid (m), approach delta_i (m), n_ix, n_iy, the curvature
    1/|P_i - d| of the approach across n_i (1/m; 0 in plane), local per-length force f_i (N/m;
    0 when delta_i <= 0), df_i/d delta_i (N/m^2))."""
    offset = slice_geometry(i, length, slices, 0.0)[0]
    px, py = ax + bx * offset - dx, ay + by * offset - dy
    if planar:
        rho, nx, ny, curvature = px, 1.0, 0.0, 0.0
    else:
        rho = math.sqrt(px * px + py * py)
        nx, ny, curvature = (px / rho, py / rho, 1.0 / rho) if rho > 0.0 else (1.0, 0.0, 0.0)
    approach = rho - clearance
    if relief_length > 0.0 and relief_depth > 0.0:
        approach -= relief.relief_at(0.5 * length + offset, 0.0, length, relief_length,
                                     relief_depth)[0]
    if approach <= 0.0:
        return offset, approach, nx, ny, curvature, 0.0, 0.0
    force, slope = tables.table_force_slope(approach, grid_log0, grid_step, table)
    return offset, approach, nx, ny, curvature, force, slope


@numba.njit(cache=True, _nrt=False)
def section_sums(dx, dy, ax, ay, bx, by, clearance, planar, length, slices, grid_log0,
                 grid_step, table, relief_length, relief_depth, end_length, scale):
    """The slices' resultants at the bore displacement (dx, dy) (slice_contact's geometry):
    (F_x, F_y (N), M_x, M_y (N m: sum of f_i z'_i w_i n_i), the stiffness -dF/dd (N/m, 2 x 2:
    K_xx, K_xy, K_yy), contact length (m)), F = a sum_i f_i w_i n_i and
    K = a sum_i w_i [f'_i n_i n_i^T + f_i / |P_i - d| (I - n_i n_i^T)]."""
    fx = fy = mx = my = kxx = kxy = kyy = contact = 0.0
    for i in range(slices):
        offset, approach, nx, ny, curvature, f, slope = slice_contact(
            i, dx, dy, ax, ay, bx, by, clearance, planar, length, slices, grid_log0, grid_step,
            table, relief_length, relief_depth)
        if approach <= 0.0:
            continue
        _, width, weight = slice_geometry(i, length, slices, end_length)
        weight *= scale
        fx += f * weight * nx
        fy += f * weight * ny
        mx += f * offset * weight * nx
        my += f * offset * weight * ny
        across = f * curvature
        kxx += weight * (slope * nx * nx + across * (1.0 - nx * nx))
        kxy += weight * (slope - across) * nx * ny
        kyy += weight * (slope * ny * ny + across * (1.0 - ny * ny))
        contact += width
    return fx, fy, mx, my, kxx, kxy, kyy, contact


@numba.njit(cache=True, _nrt=False)
def bore_displacement(ax, ay, bx, by, clearance, planar, length, slices, grid_log0, grid_step,
                      table, relief_length, relief_depth, end_length, scale, compliance):
    """The bore's uniform displacement d (m, 2: d_x, d_y) under its bulk compliance (m^2/N):
    the root of g(d) = d - compliance F(d) / L (module docstring, "The section in 2D"), the
    minimum of the strongly convex potential Psi(d) = |d|^2/2 + (compliance / L) sum_i a w_i
    U(delta_i(d)), U' = f_loc. Newton's method with the Jacobian I + (compliance / L) K (SPD)
    from d = 0; a step that overshoots the minimum along its direction (g(d + s) . s > 0) is
    cut back to it by regula falsi (Illinois) on the monotone g(d + t s) . s, so Psi falls at
    every step. |d| <= compliance |F(0)| / L (strong convexity) sets the scale of the
    tolerance, 1e-12 of it plus the section's size |P|. (0, 0) without compliance or contact
    at d = 0; NaN when F is NaN."""
    if compliance == 0.0:
        return 0.0, 0.0
    c = compliance / length
    size = math.sqrt(ax * ax + ay * ay) + 0.5 * length * math.sqrt(bx * bx + by * by)
    dx = dy = 0.0
    fx, fy, _, _, kxx, kxy, kyy, _ = section_sums(
        dx, dy, ax, ay, bx, by, clearance, planar, length, slices, grid_log0, grid_step, table,
        relief_length, relief_depth, end_length, scale)
    if not (math.isfinite(fx) and math.isfinite(fy)):
        return math.nan, math.nan
    if fx == 0.0 and fy == 0.0:
        return 0.0, 0.0
    tolerance = 1e-12 * (size + c * math.sqrt(fx * fx + fy * fy))
    gx, gy = -c * fx, -c * fy
    for _ in range(100):
        jxx, jxy, jyy = 1.0 + c * kxx, c * kxy, 1.0 + c * kyy
        det = jxx * jyy - jxy * jxy
        sx, sy = -(jyy * gx - jxy * gy) / det, -(jxx * gy - jxy * gx) / det
        if math.sqrt(sx * sx + sy * sy) <= tolerance:
            return dx + sx, dy + sy
        low, slope_low = 0.0, gx * sx + gy * sy      # < 0: s is a descent direction of Psi
        high, slope_high = 1.0, 0.0
        t, side = 1.0, 0
        for search in range(60):
            fx, fy, _, _, kxx, kxy, kyy, _ = section_sums(
                dx + t * sx, dy + t * sy, ax, ay, bx, by, clearance, planar, length, slices,
                grid_log0, grid_step, table, relief_length, relief_depth, end_length, scale)
            if not (math.isfinite(fx) and math.isfinite(fy)):
                return math.nan, math.nan
            gx, gy = dx + t * sx - c * fx, dy + t * sy - c * fy
            slope = gx * sx + gy * sy
            if slope <= 0.0 and search == 0:
                break                                 # the full Newton step
            if slope > 0.0:
                high, slope_high = t, slope
                if side > 0:
                    slope_low *= 0.5                  # Illinois: the stale end's weight halved
                side = 1
            else:
                low, slope_low = t, slope
                if side < 0:
                    slope_high *= 0.5
                side = -1
            if (high - low) * math.sqrt(sx * sx + sy * sy) <= tolerance or slope == 0.0 \
                    or search == 59:
                break
            t = (low * slope_high - high * slope_low) / (slope_high - slope_low)
        dx, dy = dx + t * sx, dy + t * sy
    return dx, dy


@numba.njit(cache=True, _nrt=False)
def shared_approach(delta, theta, length, slices, grid_log0, grid_step, table, relief_length,
                    relief_depth, end_length, scale, compliance):
    """The approach x = delta - compliance F(x) / L the slices share once the bore has moved
    by its bulk compliance (m^2/N) times F / L (module docstring): the in-plane case of
    bore_displacement. NaN when F is NaN."""
    return delta - bore_displacement(delta, 0.0, theta, 0.0, 0.0, True, length, slices,
                                     grid_log0, grid_step, table, relief_length, relief_depth,
                                     end_length, scale, compliance)[0]


@numba.njit(cache=True, _nrt=False)
def sliced(delta, theta, length, slices, grid_log0, grid_step, table, relief_length, relief_depth,
           end_length, scale, compliance):
    """(F (N), M (N m), z_F (m), contact length (m)) of a pin approached by delta (m) and
    tilted by theta (rad) in a bore of `length` (m) cut into `slices` slices, the local
    per-length law f_loc (N/m) given by its table (grid_log0, grid_step, table = ln f_loc:
    pinbore.laws.tables), the bore's edge relief over `relief_length` to `relief_depth` (m;
    0 for none), `end_length` (m) of law added at each end, the stiffness factor `scale` and
    the bulk compliance `compliance` (m^2/N; 0: independent slices):

        F = a sum_i f_loc(delta_i) w_i,   M = a sum_i f_loc(delta_i) (z_i - L/2) w_i,
        delta_i = delta - c_b F / L + theta (z_i - L/2) - r(z_i),
        w_i = L/n + end_length at i = 0 and at i = n - 1,   z_F = L/2 + M/F

    (module docstring; [Johnson1985] for the elastic-foundation idealisation). z_F is NaN
    when F = 0; F, M, z_F are NaN when a slice is beyond the table."""
    shift = bore_displacement(delta, 0.0, theta, 0.0, 0.0, True, length, slices, grid_log0,
                              grid_step, table, relief_length, relief_depth, end_length, scale,
                              compliance)[0]
    if not math.isfinite(shift):
        return math.nan, math.nan, math.nan, math.nan
    force, _, moment, _, _, _, _, contact = section_sums(
        shift, 0.0, delta, 0.0, theta, 0.0, 0.0, True, length, slices, grid_log0, grid_step,
        table, relief_length, relief_depth, end_length, scale)
    resultant = 0.5 * length + moment / force if force != 0.0 else math.nan
    return force, moment, resultant, contact


@numba.njit(cache=True)
def sliced_profile(delta, theta, length, slices, grid_log0, grid_step, table, relief_length,
                   relief_depth, end_length, scale, compliance):
    """The slices of `sliced` (same arguments): arrays of their midpoints z_i (m),
    approaches delta_i (m) and per-length forces a f_loc(delta_i) (N/m), the line load along
    the pin as the law sees it (the end lengths' share not included)."""
    shift = bore_displacement(delta, 0.0, theta, 0.0, 0.0, True, length, slices, grid_log0,
                              grid_step, table, relief_length, relief_depth, end_length, scale,
                              compliance)[0]
    z, approach, force = np.empty(slices), np.empty(slices), np.empty(slices)
    for i in range(slices):
        offset, approach[i], _, _, _, f, _ = slice_contact(
            i, shift, 0.0, delta, 0.0, theta, 0.0, 0.0, True, length, slices, grid_log0,
            grid_step, table, relief_length, relief_depth)
        force[i] = scale * f
        z[i] = 0.5 * length + offset
    return z, approach, force


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


# numba's cache follows only this file: the law compiles in the table lookup and the relief.
COMPILED_IN = (tables.__file__, relief.__file__)
follow_compiled_in(globals(), COMPILED_IN)
