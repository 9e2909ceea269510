r"""The mechanism, written once for every body kind and for the plane and space: ideal joints
and the drive, torsion springs, stops and latches, linear spring-dampers and harmonic loads
(spring_forces, load_forces), clearance joints and their contacts, the
equations of motion with their constraints, impacts, the projection onto the constraints and
the integrator's hooks. A body is reached only through reduced.mechanism.bodies (a point's
and a vector's position, velocity and Jacobian; a force pushed at a point), a vector only
through reduced.mechanism.vectors: numba compiles this module once for planar bodies
(layout.PLANAR, 2-vectors) and once for spatial ones (layout.SPATIAL, 3-vectors).

Equations of motion ([Cao2013] eq. 21; stabilised after [Baumgarte1972]), in the bodies'
velocity columns v (planar: x', y', w; spatial: r', w):

    M v' + D^T lambda = Q(q, v, t),     D v' = gamma - 2 a Phi' - a^2 Phi,

lambda from the Schur system (D M^-1 D^T) lambda = D M^-1 Q - gamma~ (the body kind's
M^-1; reduced.mechanism.linalg), then v' = M^-1 (Q - D^T lambda), and the body kind turns v'
into the coordinates' second derivatives (bodies.state_rates).

Ideal joints and the drive are primitive constraints ([Nikravesh1988] ch. 7): a point of body
i on a point of body j (POINT: D rows), a vector of i normal to a vector of j (DOT1), a vector
of i normal to the line between two points (DOT2), the relative angle about an axis (ANGLE:
angle0 + speed t). A planar revolute joint is one POINT, a planar prismatic joint a DOT2 and
an ANGLE, the planar drive an ANGLE of its body against the ground; in space a spherical joint
is a POINT, a universal one a POINT and a DOT1, a revolute a POINT and two DOT1, a cylindrical
two DOT1 and two DOT2, a prismatic the cylindrical plus a DOT1, a fixed one a POINT and three
DOT1 (reduced.mechanism.joints builds them). Each row gives its value, its Jacobian, its
explicit time rate and gamma, the velocity terms of its second derivative with the sign
changed: for a body point P'' = r'' + w' x s + w x (w x s), for a body vector
a'' = w' x a + w x (w x a).

Clearance joints are contacts (layout.CONTACT_*), each a distance that closes:
- RADIAL: a journal point X (a planar journal's centre; a ball's in its socket, the dry
  spherical joint of [FloresLankarani2010] and [Tian2009]) from a bearing point P
  (the bore's or socket's centre): delta = |X - P| - c, normal n = (X - P)/|X - P|, contact
  point C = P + R_b n;
- AXIS_RADIAL: a journal point from the bore's axis u (a cylindrical journal's end, with rigid
  impacts): delta = |(X - P) - ((X - P).u) u| - c;
- PLANE: a journal point against a face of the bearing body, normal N (body-fixed), offset d:
  delta = s N.(X - P) - d on the face's side s (a translational joint's slider corners; the
  shoulders of a cylindrical joint, two-sided: s = sgn N.(X - P), a linear penalty of the
  project's own; a calibrated joint's shoulders take chi of its e(v0) at the axial impact
  speed, though the FE impacts were radial: for the shoulders' faces that e is unverified);
- SLICED: a journal along its bore in space, cut into slices ([Cao2013]'s 3D joint, the
  sliced law of pinbore.laws.sliced with its bulk compliance): see sliced_forces.
A continuous contact carries F_n = F_el(delta) (1 + chi delta'/v0) while delta > 0, F_el from
a table of the elastic law (pinbore.laws.tables) or a linear law, chi the hysteresis factor of
the damping law (or, calibrated, of the laws file's e(v0) at v0), v0 the approach rate at the
onset of this impact; friction opposes the slip at the contact point: Ambrosio's regularised
Coulomb, the polynomial Stribeck or the linear velocity law (static), LuGre or Dahl
normalised by F_n, or the bilinear Iwan element, whose states are integrated with the motion
and rest while the contact is open. In the plane the slip is the component along the tangent
(-n_y, n_x) and a state law's state is a float along it; in space the slip is the relative
velocity less its normal part and a state is a vector kept in the bearing body's frame, of
which the tangent part acts (each slice of a journal has its own). Impulse contacts (Newton
or Poisson): rigid impacts between steps (apply_impulse), and below a rest speed held
contact: the constraint delta = 0 joins the ideal ones until its multiplier (the normal force)
would pull. The normal force and every friction law are the functions of pinbore.laws.
dissipative and pinbore.laws.friction, compiled in. While delta <= 0 no law is evaluated.

Extra states integrate the energy dissipated in the contacts, torsion dampers and
spring-dampers and the work of the constraint forces (the drive) and of the harmonic loads,
so the energy balance can be checked.

The integrators are reduced.mechanism.integrator's; this module implements its hooks. A step
ends at its first event (event_fraction): a step that would carry a contact from free flight
into contact deeper than `onset_tol` is shortened (secant on delta) until it ends at the
onset, where v0 is recorded; latches engage the same way, at their angle, so their spring
starts unloaded, and held contacts release at the zero of their force. The accepted step's
updates (after_step) come then, and, where the drift exceeds the onset tolerance, the
projection of positions and velocities back onto the constraints (one mass-weighted
Gauss-Newton step each), so drift cannot accumulate where Baumgarte alone is too slow.

The arithmetic is, operation by operation, the one the planar and the spatial models did
before they were written as one (their shipped scenes give the same numbers to the last bit):
where the two differed in a rounding, the body kind or the vector's dimension decides (the
body's own functions in reduced.mechanism.bodies, vectors' `norm` and `direction`), and a
RADIAL contact applies its normal force at the contact point on both bodies when its row says
so (the planar revolute joint) and at the two centres otherwise (the ball).
"""

import math
import warnings

import numba
import numpy as np
from numba.core.errors import NumbaIRAssumptionWarning
from numba.extending import overload

from pinbore.core.compiled import beside, follow_compiled_in
from pinbore.laws import dissipative, friction, sliced, tables
from pinbore.reduced.mechanism import bodies, integrator, layout, linalg, vectors
from pinbore.reduced.mechanism.bodies import (
    body_columns, body_forces, body_states, centripetal_gap, dot1, fill_schur, kinetic_energy,
    material_velocity, normalise, point_state, position_step, push, push_torque, put,
    relative_rotation, rotation_axis, row_rate, state_rates, turned, unturned, vector_state,
    velocity_step)
from pinbore.reduced.mechanism.layout import (
    ANGLE, AXIS_RADIAL, CHI_POINTS, CONTACT_AT_CONTACT, CONTACT_BEARING_AXIS, CONTACT_BEARING_BODY,
    CONTACT_BEARING_POINT, CONTACT_CHI, CONTACT_CHI_LOG_SPEED, CONTACT_CHI_STEP, CONTACT_CHI_TABLE,
    CONTACT_CLEARANCE, CONTACT_COMPLIANCE, CONTACT_END_LENGTH, CONTACT_FRICTION_LAW,
    CONTACT_FRICTION_ON, CONTACT_IMPACT, CONTACT_JOINT, CONTACT_JOURNAL_AXIS, CONTACT_JOURNAL_BODY,
    CONTACT_JOURNAL_POINT, CONTACT_KIND, CONTACT_LENGTH, CONTACT_RADIUS, CONTACT_RESTITUTION,
    CONTACT_REST_SPEED, CONTACT_SCALE, CONTACT_SIDE, CONTACT_SLICES, CONTACT_STATE,
    CONTACT_STIFFNESS, CONTACT_TABLE, CONTINUOUS, COULOMB, COULOMB_MU, DAHL, DAHL_MU, DAHL_SIGMA,
    DISSIPATED, DOT1, DOT2, ENERGY_STATES, HARMONIC, HARM_AMPLITUDE, HARM_OMEGA, HARM_PHASE, IWAN,
    IWAN_K1, IWAN_K2, IWAN_MU, LATCH, LINEAR, LINEAR_ALPHA, LINEAR_MU_STATIC, LOAD_BODY,
    LOAD_FORCE, LOAD_OMEGA, LOAD_PHASE, LOAD_POINT, LOAD_TORQUE, LOG_COLUMNS, LOG_IMPULSE,
    LOG_JOINT, LOG_RATE, LOG_TIME, LUGRE, LUGRE_MU_COULOMB, LUGRE_MU_STATIC, LUGRE_SIGMA0,
    LUGRE_SIGMA1, LUGRE_SIGMA2, LUGRE_STRIBECK_SPEED, NO_FRICTION, PLANE, POINT, POISSON,
    PRIM_ANGLE0, PRIM_A_I, PRIM_BODY_I, PRIM_BODY_J, PRIM_B_J, PRIM_C_I, PRIM_KIND, PRIM_PROFILE,
    PRIM_PROFILE_ROWS, PRIM_PROFILE_TIME, PRIM_SPEED, PRIM_S_I, PRIM_S_J, RADIAL,
    REGULARISATION_V0, REGULARISATION_V1, SEG_C0, SEG_C1, SEG_C2, SEG_C3, SEG_TIME, SLICED,
    SPIN_UP, SPRING_BODY_I, SPRING_BODY_J, SPRING_DAMPING, SPRING_LENGTH, SPRING_STIFFNESS,
    SPRING_S_I, SPRING_S_J, STATE_STRETCH, STATE_TRAVEL, STOP, STRIBECK, STRIBECK_MU_MIN,
    STRIBECK_MU_STATIC, STRIBECK_V_MIN, TABLE, TORSION_A_I, TORSION_BODY_I, TORSION_BODY_J,
    TORSION_B_J, TORSION_C_I, TORSION_DAMPING, TORSION_FREE_ANGLE, TORSION_KIND, TORSION_STIFFNESS,
    TORSION_S_I, TORSION_S_J, WORK_IN, Contacts, Depth, Impulse, Work)
from pinbore.reduced.mechanism.linalg import cholesky_solve
from pinbore.reduced.mechanism.vectors import (
    _plane, _space, add, angular_cell, angular_zero, axis, cell, cross, direction, dot, negated, norm,
    scaled, sub, tangent, zero)

LATCH_TOL = 1e-8   # rad: a latch engages within this of its angle (the step is shortened to it)

# numba's inliner checks the SSA form of what it inlines and warns of a variable "not in scope"
# when a function that assigns in branches is inlined. Where it was right, the function is not
# inlined (`start`: inlined, it lost the contacts found in contact at a restart); the inlined
# right-hand side gives the numbers of the closed forms and of the models written before this
# engine to the last bit (the tests), so the warning is not the user's concern.
warnings.filterwarnings("ignore", category=NumbaIRAssumptionWarning)


# ---- the constraint rows
@numba.njit(cache=True, _nrt=False)
def constraint_count(primitives, like):
    """Rows of the ideal joints and the drive (held contacts come on top)."""
    m = 0
    for k in range(primitives.shape[0]):
        m += len(like) if int(primitives[k, PRIM_KIND]) == POINT else 1
    return m


@numba.njit(cache=True, _nrt=False, inline="always")
def sorted_bodies(row_bodies, row, bi, bj):
    """The two bodies of a constraint row, ascending (-1: none)."""
    if bj == bi:
        bj = -1
    row_bodies[row, 0], row_bodies[row, 1] = min(bi, bj), max(bi, bj)


@numba.njit(cache=True)
def constraint_pattern(primitives, m, like):
    """The fixed sparsity of the ideal rows (each row's two bodies; a row has nonzero Jacobian
    columns for these only) and the envelope of the Schur matrix (linalg); the rows of held
    contacts, after them, are dense (first 0)."""
    row_bodies = np.full((m, 2), -1, np.int64)
    row = 0
    for k in range(primitives.shape[0]):
        kind, bi, bj = (int(primitives[k, PRIM_KIND]), int(primitives[k, PRIM_BODY_I]),
                        int(primitives[k, PRIM_BODY_J]))
        for c in range(len(like) if kind == POINT else 1):
            sorted_bodies(row_bodies, row + c, bi, bj)
        row += len(like) if kind == POINT else 1
    first = np.zeros(m, np.int64)
    linalg.envelope_of(row_bodies, first, 0, row)
    return row_bodies, first


@numba.njit(cache=True, _nrt=False, inline="always")
def clear_row(jac, row, b, offsets):
    if b >= 0:
        for c in range(offsets[b], offsets[b + 1]):
            jac[row, c] = 0.0


@numba.njit(cache=True, _nrt=False, inline="always")
def constraint_rate(jac, phi_t, row_bodies, states, velocities, i, offsets, like):
    """Phi' of constraint row i: D_i v + Phi_t (the row's two bodies only)."""
    rate = phi_t[i]
    for side in range(2):
        b = row_bodies[i, side]
        if b >= 0:
            rate = row_rate(rate, jac, i, b, states, velocities, offsets, like)
    return rate


@numba.njit(cache=True, _nrt=False)
def spin_up(t, speed, duration):
    """The smooth spin-up to `speed` (rad/s) over `duration` (s) [SimoVuQuoc1986]:

        theta(t) = (w_s / T_s) (t^2 / 2 + (T_s / 2 pi)^2 (cos(2 pi t / T_s) - 1)),  t < T_s,
        theta(t) = w_s (t - T_s / 2),                                               t >= T_s,

    (theta (rad), its rate (rad/s), its acceleration (rad/s^2)): rate and acceleration
    continuous, the acceleration zero at both ends of the spin-up."""
    if t >= duration:
        return speed * (t - duration / 2), speed, 0.0
    w = 2 * math.pi / duration
    k = speed / duration
    return (k * (t * t / 2 + (math.cos(w * t) - 1) / (w * w)), k * (t - math.sin(w * t) / w),
            k * (1 - math.cos(w * t)))


@numba.njit(cache=True, _nrt=False)
def drive_profile(primitives, k, profile, t):
    """theta(t) of the ANGLE primitive k (layout.PRIM_PROFILE): its value (rad), rate and
    acceleration; a table's segment found by bisection, a harmonic drive's sum in closed form."""
    kind, speed = int(primitives[k, PRIM_PROFILE]), primitives[k, PRIM_SPEED]
    if kind == SPIN_UP:
        return spin_up(t, speed, primitives[k, PRIM_PROFILE_TIME])
    if kind == HARMONIC:   # theta = sum A (sin(w t + phi) - sin phi): a support shaken
        theta, rate, acceleration = 0.0, 0.0, 0.0
        first = int(primitives[k, PRIM_PROFILE_TIME])
        for i in range(first, first + int(primitives[k, PRIM_PROFILE_ROWS])):
            a, w, phase = profile[i, HARM_AMPLITUDE], profile[i, HARM_OMEGA], profile[i, HARM_PHASE]
            sine = math.sin(w * t + phase)
            theta += a * (sine - math.sin(phase))
            rate += a * w * math.cos(w * t + phase)
            acceleration -= a * w * w * sine
        return theta, rate, acceleration
    if kind == TABLE:
        i = int(primitives[k, PRIM_PROFILE_TIME])   # the last segment starting at or before t
        last = i + int(primitives[k, PRIM_PROFILE_ROWS]) - 1
        while i < last:
            middle = (i + last + 1) // 2
            if profile[middle, SEG_TIME] <= t:
                i = middle
            else:
                last = middle - 1
        tau = t - profile[i, SEG_TIME]
        c1, c2, c3 = profile[i, SEG_C1], profile[i, SEG_C2], profile[i, SEG_C3]
        return (profile[i, SEG_C0] + tau * (c1 + tau * (c2 + tau * c3)),
                c1 + tau * (2 * c2 + 3 * c3 * tau), 2 * c2 + 6 * c3 * tau)
    return speed * t, speed, 0.0


@numba.njit(cache=True, _nrt=False)
def constraint_rows(t, primitives, profile, contacts, mode, offsets, states, velocities, jac, mjac,
                    phi, phi_t, rhs_c, row_bodies, alpha, z):
    """fill_constraints on the arrays."""
    row = 0
    for k in range(primitives.shape[0]):
        # entries read in place: a row view of `primitives` would count its references
        kind, bi, bj = (int(primitives[k, PRIM_KIND]), int(primitives[k, PRIM_BODY_I]),
                        int(primitives[k, PRIM_BODY_J]))
        for c in range(len(z) if kind == POINT else 1):
            clear_row(jac, row + c, row_bodies[row + c, 0], offsets)
            clear_row(jac, row + c, row_bodies[row + c, 1], offsets)
        if kind == POINT:
            pi, _, ci, si = point_state(states, bi, cell(primitives, k, PRIM_S_I, z))
            pj, _, cj, sj = point_state(states, bj, cell(primitives, k, PRIM_S_J, z))
            for c in range(len(z)):
                unit = axis(c, z)
                put(jac, row + c, states, bi, cell(primitives, k, PRIM_S_I, z), unit, cross(si, unit), 1.0, offsets)
                put(jac, row + c, states, bj, cell(primitives, k, PRIM_S_J, z), unit, cross(sj, unit), -1.0, offsets)
                phi[row + c], phi_t[row + c], rhs_c[row + c] = pi[c] - pj[c], 0.0, cj[c] - ci[c]
            row += len(z)
            continue
        if kind == DOT1:
            s_i, s_j = cell(primitives, k, PRIM_S_I, z), cell(primitives, k, PRIM_S_J, z)
            value, coefficient, _, acc = dot1(states, bi, s_i, cell(primitives, k, PRIM_A_I, z), bj,
                                              s_j, cell(primitives, k, PRIM_B_J, z))
            put(jac, row, states, bi, s_i, zero(z), coefficient, 1.0, offsets)
            put(jac, row, states, bj, s_j, zero(z), coefficient, -1.0, offsets)
            phi[row], phi_t[row], rhs_c[row] = value, 0.0, -acc
        elif kind == DOT2:
            value, gamma = dot2_row(jac, row, states, bi, cell(primitives, k, PRIM_S_I, z),
                                    cell(primitives, k, PRIM_A_I, z), bj,
                                    cell(primitives, k, PRIM_S_J, z), offsets)
            phi[row], phi_t[row], rhs_c[row] = value, 0.0, gamma
        else:   # ANGLE: the relative angle = angle0 + theta(t)
            theta, rate, acceleration = drive_profile(primitives, k, profile, t)
            s_i, s_j = cell(primitives, k, PRIM_S_I, z), cell(primitives, k, PRIM_S_J, z)
            angle, coefficient, _, gamma = relative_rotation(
                states, bi, bj, s_i, s_j, cell(primitives, k, PRIM_A_I, z),
                cell(primitives, k, PRIM_B_J, z), cell(primitives, k, PRIM_C_I, z),
                primitives[k, PRIM_ANGLE0], theta)
            put(jac, row, states, bi, s_i, zero(z), coefficient, 1.0, offsets)
            put(jac, row, states, bj, s_j, zero(z), coefficient, -1.0, offsets)
            phi[row], phi_t[row], rhs_c[row] = angle, 0.0 - rate, gamma + acceleration
        row += 1
    for k in range(contacts.shape[0]):
        if mode[k] == 1:
            held_row(jac, mjac, phi, phi_t, rhs_c, row_bodies, row, states, contacts, k, offsets, z)
            row += 1
    for i in range(row):
        rhs_c[i] -= (2 * alpha * constraint_rate(jac, phi_t, row_bodies, states, velocities, i, offsets, z)
                     + alpha * alpha * phi[i])
    return row


@numba.njit(cache=True, _nrt=False)
def dot2_row(jac, row, states, bi, s_i, a_i, bj, s_j, offsets):
    """The dot-2 row a_i . (P_j - P_i) (a vector of body i normal to the line from a point of
    body i to one of body j) into row `row` of jac: (its value, its gamma)."""
    a, ad, ac = vector_state(states, bi, s_i, a_i)
    pi, vi, ci, si = point_state(states, bi, s_i)
    pj, vj, cj, sj = point_state(states, bj, s_j)
    d, dd = sub(pj, pi), sub(vj, vi)
    put(jac, row, states, bi, s_i, scaled(a, -1.0), cross(a, add(d, si)), 1.0, offsets)
    put(jac, row, states, bj, s_j, a, cross(sj, a), 1.0, offsets)
    return dot(a, d), -(dot(ac, d) + 2 * dot(ad, dd) + centripetal_gap(states, a, bi, si, ci, bj, sj, cj))


@numba.njit(cache=True, _nrt=False)
def held_row(jac, mjac, phi, phi_t, rhs_c, row_bodies, row, states, contacts, k, offsets, z):
    """The row of a held contact, delta = 0 (the multiplier is its normal force)."""
    bb, bj = int(contacts[k, CONTACT_BEARING_BODY]), int(contacts[k, CONTACT_JOURNAL_BODY])
    for c in range(jac.shape[1]):   # the row's bodies change with the contacts held
        jac[row, c] = mjac[row, c] = 0.0
    sorted_bodies(row_bodies, row, bb, bj)
    phi_t[row] = 0.0
    if int(contacts[k, CONTACT_KIND]) == PLANE:
        g = plane_geometry(states, contacts, k, z)
        value, gamma = dot2_row(jac, row, states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z),
                                scaled(cell(contacts, k, CONTACT_BEARING_AXIS, z), g.side), bj,
                                cell(contacts, k, CONTACT_JOURNAL_POINT, z), offsets)
        phi[row], rhs_c[row] = g.delta, gamma
        return
    # |e| - c with e = X - B, B the bearing point (or its foot on the bore's axis u):
    # delta'' = n.(c_J - c_B) + (|e'|^2 - s'(u.e') - (n.e')^2)/|e| - s' n.u' + D v'
    g = radial_geometry(states, contacts, k, z)
    s_j = cell(contacts, k, CONTACT_JOURNAL_POINT, z)
    pj, vj, cj, sj = point_state(states, bj, s_j)
    u, ud, _ = vector_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z),
                            cell(contacts, k, CONTACT_BEARING_AXIS, z))
    foot = add(cell(contacts, k, CONTACT_BEARING_POINT, z),
               scaled(cell(contacts, k, CONTACT_BEARING_AXIS, z), g.along))
    pb, vb, cb, sb = point_state(states, bb, foot)
    n = g.normal
    put(jac, row, states, bj, s_j, n, cross(sj, n), 1.0, offsets)
    put(jac, row, states, bb, foot, n, cross(sb, n), -1.0, offsets)
    e_dot = sub(vj, vb)
    along_rate = dot(ud, sub(pj, pb)) + dot(u, e_dot)
    size = g.delta + contacts[k, CONTACT_CLEARANCE]
    rhs_c[row] = -centripetal_gap(states, n, bb, sb, cb, bj, sj, cj)
    rhs_c[row] -= (dot(e_dot, e_dot) - along_rate * dot(u, e_dot) - g.rate * g.rate) / size
    rhs_c[row] += along_rate * dot(n, ud)
    phi[row] = g.delta


# ---- contact geometry
Radial = __import__("collections").namedtuple(
    "Radial", ["delta", "normal", "point", "rate", "at_journal", "at_bearing", "along", "relative"])
Plane = __import__("collections").namedtuple(
    "Plane", ["delta", "normal", "point", "rate", "side", "relative"])


@numba.njit(cache=True, _nrt=False)
def radial_geometry(states, contacts, k, z):
    """A RADIAL or AXIS_RADIAL contact: penetration delta = |e| - c, normal n, contact point
    C = B + R_b n, approach rate n.(v_J - v_B) at the points the normal force acts at (C on
    both when CONTACT_AT_CONTACT, else the journal point X and the bearing point B), those two
    points, the axial offset s = u.(X - P) of B = P + s u on the bore's axis (0 without an
    axis) and the relative velocity at the two points."""
    bb, bj = int(contacts[k, CONTACT_BEARING_BODY]), int(contacts[k, CONTACT_JOURNAL_BODY])
    pb = point_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z))[0]
    pj = point_state(states, bj, cell(contacts, k, CONTACT_JOURNAL_POINT, z))[0]
    e = sub(pj, pb)
    along = 0.0
    if int(contacts[k, CONTACT_KIND]) == AXIS_RADIAL:
        u = vector_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z),
                         cell(contacts, k, CONTACT_BEARING_AXIS, z))[0]
        along = dot(u, e)
        pb = add(pb, scaled(u, along))
        e = sub(e, scaled(u, along))
    size = norm(e)
    delta = size - contacts[k, CONTACT_CLEARANCE]
    if size == 0.0:
        return Radial(delta, axis(0, z), pb, 0.0, pj, pb, along, zero(z))
    n = direction(e, size)
    c = add(pb, scaled(n, contacts[k, CONTACT_RADIUS]))
    xj, xb = (c, c) if contacts[k, CONTACT_AT_CONTACT] > 0.0 else (pj, pb)
    v = sub(material_velocity(states, bj, xj), material_velocity(states, bb, xb))
    return Radial(delta, n, c, dot(n, v), xj, xb, along, v)


@numba.njit(cache=True, _nrt=False)
def plane_geometry(states, contacts, k, z):
    """A PLANE contact: the journal point X against the face of normal s N through the
    bearing point P at offset d: delta = s N.(X - P) - d (s the contact's side; two-sided: the
    sign of N.(X - P)), the normal s N, the contact point X, the approach rate
    s N.(v_J(X) - v_B(X)), the side and the relative velocity at X."""
    bb, bj = int(contacts[k, CONTACT_BEARING_BODY]), int(contacts[k, CONTACT_JOURNAL_BODY])
    p = point_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z))[0]
    u = vector_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z),
                     cell(contacts, k, CONTACT_BEARING_AXIS, z))[0]
    x = point_state(states, bj, cell(contacts, k, CONTACT_JOURNAL_POINT, z))[0]
    s = dot(sub(x, p), u)
    side = contacts[k, CONTACT_SIDE]
    if side == 0.0:
        side = 1.0 if s >= 0.0 else -1.0
        delta = abs(s) - contacts[k, CONTACT_CLEARANCE]
    else:
        delta = side * s - contacts[k, CONTACT_CLEARANCE]
    n = u if side > 0.0 else scaled(u, -1.0)
    v = sub(material_velocity(states, bj, x), material_velocity(states, bb, x))
    return Plane(delta, n, x, dot(n, v), side, v)


@numba.njit(cache=True, _nrt=False)
def contact_depth(states, contacts, k, z):
    """The deepest penetration of a contact and its approach rate there (layout.Depth)."""
    kind = int(contacts[k, CONTACT_KIND])
    if kind == PLANE:
        g = plane_geometry(states, contacts, k, z)
        return Depth(g.delta, g.rate)
    if kind == SLICED:
        return sliced_depth(states, contacts, k, z)
    g = radial_geometry(states, contacts, k, z)
    return Depth(g.delta, g.rate)


# ---- contact laws
@numba.njit(cache=True, _nrt=False)
def contact_chi(contacts, k, impact_speed):
    """The hysteresis factor chi of a contact for the impact speed v0 of its contact: the
    damping law's constant, or (damping_law = "calibrated") the tabulated chi(v0) interpolated
    linearly in ln v0, held at the table's ends."""
    step = contacts[k, CONTACT_CHI_STEP]
    if step == 0.0:
        return contacts[k, CONTACT_CHI]
    x = (math.log(impact_speed) - contacts[k, CONTACT_CHI_LOG_SPEED]) / step
    if x <= 0.0:
        return contacts[k, CONTACT_CHI_TABLE]
    if x >= CHI_POINTS - 1:
        return contacts[k, CONTACT_CHI_TABLE + CHI_POINTS - 1]
    i = int(x)
    f = x - i
    return (1.0 - f) * contacts[k, CONTACT_CHI_TABLE + i] + f * contacts[k, CONTACT_CHI_TABLE + i + 1]


@numba.njit(cache=True, _nrt=False)
def static_coefficient(contact, slip):
    """mu of a static friction law at the slip speed (COULOMB, STRIBECK, LINEAR)."""
    law = int(contact[CONTACT_FRICTION_LAW])
    if law == COULOMB:
        return contact[COULOMB_MU]
    if law == STRIBECK:
        return friction.stribeck_polynomial(slip, contact[STRIBECK_MU_STATIC], contact[STRIBECK_MU_MIN],
                                            contact[STRIBECK_V_MIN])
    return friction.linear_velocity(slip, contact[LINEAR_MU_STATIC], contact[LINEAR_ALPHA])


@numba.njit(cache=True, _nrt=False)
def scalar_friction(contact, f_n, slip, state):
    """Friction force (N, along the slip: it acts against it) and the rate of the law's state,
    for every law but the two-state Iwan element: the laws of pinbore.laws.friction with the
    contact's parameters, LuGre and Dahl normalised by F_n."""
    law = int(contact[CONTACT_FRICTION_LAW])
    if law == NO_FRICTION:
        return 0.0, 0.0
    if law <= LINEAR:   # static laws, regularised (Ambrosio)
        return friction.ambrosio(slip, f_n, static_coefficient(contact, slip), contact[REGULARISATION_V0],
                                 contact[REGULARISATION_V1]), 0.0
    if law == LUGRE:
        g = friction.lugre_g(slip, contact[LUGRE_MU_COULOMB], contact[LUGRE_MU_STATIC],
                             contact[LUGRE_STRIBECK_SPEED])
        rate = friction.lugre_rate(state, slip, contact[LUGRE_SIGMA0], g)
        return f_n * friction.lugre_force(state, rate, slip, contact[LUGRE_SIGMA0], contact[LUGRE_SIGMA1],
                                          contact[LUGRE_SIGMA2]), rate
    return f_n * state, friction.dahl_rate(state, slip, contact[DAHL_SIGMA], contact[DAHL_MU])


@numba.njit(cache=True, _nrt=False)
def planar_friction(contacts, k, f_n, n, v, y, dy, index):
    """Friction at a contact in the plane: the slip v.t along the tangent t = (-n_y, n_x), the
    law's force along it and its states' rates into dy. (force on the journal, power, the
    law's force f_t: the journal is pushed by -f_t t)."""
    t = tangent(n)
    slip = dot(t, v)
    contact = contacts[k]
    if int(contact[CONTACT_FRICTION_LAW]) == IWAN:
        f_t, rate0, rate1 = friction.iwan_bilinear(y[index + STATE_TRAVEL], y[index + STATE_STRETCH],
                                                   slip, contact[IWAN_K1], contact[IWAN_K2],
                                                   contact[IWAN_MU] * f_n)
        dy[index] = rate0
        dy[index + STATE_STRETCH] = rate1
    else:
        f_t, rate0 = scalar_friction(contact, f_n, slip, y[index] if index >= 0 else 0.0)
        if index >= 0:
            dy[index] = rate0
    return scaled(t, -f_t), f_t * slip, f_t


@numba.njit(cache=True, _nrt=False)
def spatial_friction(states, contacts, k, f_n, n, v, y, dy, index, spin, share):
    """Friction at a contact in space: the slip v - n (v.n) and the law's force against it; a
    state law's state is a vector in the bearing body's frame, of which the part tangent to
    the contact acts (LuGre: z' = v - sigma0 |v| z / g(|v|), F = F_n (sigma0 z + sigma1 z' +
    sigma2 v); Dahl: m' = sigma (v - m |v| / mu), F = F_n m; Iwan: travel x' = v, stretch z'
    = v (sticking) or its part across z (sliding, |k1 z| = mu F_n), F = k1 z + k2 x): the
    planar laws for a slip of any direction. A state is carried with the contact's frame: as
    the normal turns against the bearing body at `spin` (n' relative to the bearing, global
    components) its rate gains -n (n'.z), which keeps it tangent; in the plane that is exactly
    the planar law's scalar state along the turning tangent (z = s t, z' = s' t - s theta' n).
    An Iwan element of a slice carries its `share` of the joint's stiffnesses k1, k2 (its part
    of the length; its strength is its own mu F_n). (force on the journal, power, the force's
    size)."""
    law = int(contacts[k, CONTACT_FRICTION_LAW])
    slip = sub(v, scaled(n, dot(v, n)))
    speed = math.sqrt(dot(slip, slip))
    if law <= LINEAR:
        if speed > 0.0:
            f_t = scalar_friction(contacts[k], f_n, speed, 0.0)[0]
            return scaled(slip, -f_t / speed), f_t * speed, f_t
        return (0.0, 0.0, 0.0), 0.0, 0.0
    bb = int(contacts[k, CONTACT_BEARING_BODY])
    state = index + 3 * STATE_STRETCH if law == IWAN else index   # the stretch, or the state
    z = turned(states, bb, (y[state], y[state + 1], y[state + 2]))
    z = sub(z, scaled(n, dot(z, n)))
    if law == LUGRE:
        sigma0 = contacts[k, LUGRE_SIGMA0]
        g = friction.lugre_g(speed, contacts[k, LUGRE_MU_COULOMB], contacts[k, LUGRE_MU_STATIC],
                             contacts[k, LUGRE_STRIBECK_SPEED])
        rate = sub(slip, scaled(z, sigma0 * speed / g))
        f = scaled(add(add(scaled(z, sigma0), scaled(rate, contacts[k, LUGRE_SIGMA1])),
                       scaled(slip, contacts[k, LUGRE_SIGMA2])), f_n)
        rate = sub(rate, scaled(n, dot(spin, z)))
    elif law == DAHL:
        mu = contacts[k, DAHL_MU]
        rate = sub(scaled(sub(slip, scaled(z, speed / mu)), contacts[k, DAHL_SIGMA]),
                   scaled(n, dot(spin, z)))
        f = scaled(z, f_n)
    else:   # IWAN: travel then stretch
        k1 = share * contacts[k, IWAN_K1]
        limit = contacts[k, IWAN_MU] * f_n / k1
        travel = turned(states, bb, (y[index], y[index + 1], y[index + 2]))
        travel = sub(travel, scaled(n, dot(travel, n)))
        size = math.sqrt(dot(z, z))
        rate = slip
        if size >= limit and dot(z, slip) > 0.0:   # sliding: the stretch turns, its size held
            rate = sub(slip, scaled(z, dot(z, slip) / (size * size)))
        held = scaled(z, limit / size) if size > limit else z
        f = add(scaled(held, k1), scaled(travel, share * contacts[k, IWAN_K2]))
        rate = sub(rate, scaled(n, dot(spin, z)))
        moved = unturned(states, bb, sub(slip, scaled(n, dot(spin, travel))))
        dy[index], dy[index + 1], dy[index + 2] = moved[0], moved[1], moved[2]
    moved = unturned(states, bb, rate)
    dy[state], dy[state + 1], dy[state + 2] = moved[0], moved[1], moved[2]
    return negated(f), dot(f, slip), math.sqrt(dot(f, f))


def contact_friction(states, contacts, k, f_n, n, v, y, dy, index, xj, delta):
    """Friction at a contact point (planar_friction; spatial_friction, with the normal's turn
    against the bearing body (normal_spin) that a vector state follows, by the dimension)."""


@overload(contact_friction, jit_options={"_nrt": False})
def _contact_friction(states, contacts, k, f_n, n, v, y, dy, index, xj, delta):
    if _plane(n):
        return lambda states, contacts, k, f_n, n, v, y, dy, index, xj, delta: planar_friction(
            contacts, k, f_n, n, v, y, dy, index)
    if _space(n):
        return lambda states, contacts, k, f_n, n, v, y, dy, index, xj, delta: spatial_friction(
            states, contacts, k, f_n, n, v, y, dy, index,
            normal_spin(states, contacts, k, n, xj, delta), 1.0)


@numba.njit(cache=True, _nrt=False)
def normal_spin(states, contacts, k, n, x, delta):
    """n' against the bearing body of a point contact in space (global components): zero for
    a face (PLANE: its normal is the bearing's); for a journal point x at |e| = delta + c from
    the bearing point, the relative velocity v_j(x) - v_b(x) across n over |e| (a state law
    needs it only; the others do not read it)."""
    if int(contacts[k, CONTACT_KIND]) == PLANE or int(contacts[k, CONTACT_FRICTION_LAW]) <= LINEAR:
        return (0.0, 0.0, 0.0)
    w = sub(material_velocity(states, int(contacts[k, CONTACT_JOURNAL_BODY]), x),
            material_velocity(states, int(contacts[k, CONTACT_BEARING_BODY]), x))
    return scaled(sub(w, scaled(n, dot(n, w))), 1.0 / (delta + contacts[k, CONTACT_CLEARANCE]))


@numba.njit(cache=True, _nrt=False)
def elastic_force(contacts, k, delta, grid_log0, grid_step, tables_):
    """F_el(delta) of a contact: its linear law, or its table (NaN beyond it)."""
    stiffness = contacts[k, CONTACT_STIFFNESS]
    if stiffness > 0.0:
        return stiffness * delta
    return tables.table_force(delta, grid_log0, grid_step, tables_[int(contacts[k, CONTACT_TABLE])])


@numba.njit(cache=True, _nrt=False)
def point_contact(force, y, dy, states, contacts, offsets, k, speed, grid_log0, grid_step, tables_,
                  normal, friction, z):
    """The forces of a continuous RADIAL, AXIS_RADIAL or PLANE contact into `force` (its normal
    force into normal[k], its friction force into friction[k]: the law's signed f_t in the
    plane, the size in space; its friction states' rates into dy), its impact speed `speed`:
    its dissipated power (NaN beyond its law's table; 0 when open)."""
    bb, bj = int(contacts[k, CONTACT_BEARING_BODY]), int(contacts[k, CONTACT_JOURNAL_BODY])
    if int(contacts[k, CONTACT_KIND]) == PLANE:
        p = plane_geometry(states, contacts, k, z)
        delta, n, rate, c, v = p.delta, p.normal, p.rate, p.point, p.relative
        xj, xb, at_contact = c, c, True
    else:
        g = radial_geometry(states, contacts, k, z)
        delta, n, rate, c, v = g.delta, g.normal, g.rate, g.point, g.relative
        xj, xb, at_contact = g.at_journal, g.at_bearing, contacts[k, CONTACT_AT_CONTACT] > 0.0
    if delta <= 0.0:
        return 0.0
    f_el = elastic_force(contacts, k, delta, grid_log0, grid_step, tables_)
    f_n = dissipative.hysteresis_force(f_el, rate, speed, contact_chi(contacts, k, speed))
    if not math.isfinite(f_n):
        return math.nan
    normal[k] = f_n
    index = int(contacts[k, CONTACT_STATE])
    rubbing = contacts[k, CONTACT_FRICTION_ON] > 0.0 and int(contacts[k, CONTACT_FRICTION_LAW]) != NO_FRICTION
    if at_contact:   # normal force and friction at the contact point, on both bodies
        power = (f_n - f_el) * rate
        f = scaled(n, -f_n)
        if rubbing or len(z) == 2:
            f_t, p_t, friction[k] = contact_friction(states, contacts, k, f_n, n, v, y, dy, index,
                                                     xj, delta)
            f = add(f, f_t)
            power = power + p_t
        push(force, states, bj, f, c, offsets)
        push(force, states, bb, negated(f), c, offsets)
        return power
    push(force, states, bj, scaled(n, -f_n), xj, offsets)
    push(force, states, bb, scaled(n, f_n), xb, offsets)
    power = (f_n - f_el) * rate
    if rubbing:   # friction at the contact point, against the slip there
        v = sub(material_velocity(states, bj, c), material_velocity(states, bb, c))
        f_t, p_t, friction[k] = contact_friction(states, contacts, k, f_n, n, v, y, dy, index,
                                                 xj, delta)
        if p_t != 0.0 or dot(f_t, f_t) > 0.0:
            push(force, states, bj, f_t, c, offsets)
            push(force, states, bb, negated(f_t), c, offsets)
            power += p_t
    return power


# ---- a journal along its bore (space only)
@numba.njit(cache=True, _nrt=False)
def bore_section(states, contacts, k, z):
    """A SLICED contact in its bore's section: (P_j, u_j, u_b, the mid-plane eccentricity
    a0 = perp(P_j - P_b), the lean a1 = perp(u_j - u_b)), perp the part normal to u_b: the
    journal's axis point X(z) = P_j + z u_j is off the bore's axis by a0 + z a1 across it."""
    bb, bj = int(contacts[k, CONTACT_BEARING_BODY]), int(contacts[k, CONTACT_JOURNAL_BODY])
    pb = point_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z))[0]
    ub = vector_state(states, bb, cell(contacts, k, CONTACT_BEARING_POINT, z),
                      cell(contacts, k, CONTACT_BEARING_AXIS, z))[0]
    pj = point_state(states, bj, cell(contacts, k, CONTACT_JOURNAL_POINT, z))[0]
    uj = vector_state(states, bj, cell(contacts, k, CONTACT_JOURNAL_POINT, z),
                      cell(contacts, k, CONTACT_JOURNAL_AXIS, z))[0]
    e, lean = sub(pj, pb), sub(uj, ub)
    return pj, uj, ub, sub(e, scaled(ub, dot(e, ub))), sub(lean, scaled(ub, dot(lean, ub)))


@numba.njit(cache=True, _nrt=False)
def end_offset(contacts, k):
    """The offset z' of the last slice from the mid-plane (m; the first's is -z')."""
    slices = int(contacts[k, CONTACT_SLICES])
    return sliced.slice_geometry(slices - 1, contacts[k, CONTACT_LENGTH], slices, 0.0)[0]


@numba.njit(cache=True, _nrt=False)
def slice_rate(states, contacts, k, n, x, b):
    """The approach rate n . (v_journal(x) - v_bore(b)) of the material points x, b (m/s)."""
    return dot(n, sub(material_velocity(states, int(contacts[k, CONTACT_JOURNAL_BODY]), x),
                      material_velocity(states, int(contacts[k, CONTACT_BEARING_BODY]), b)))


@numba.njit(cache=True, _nrt=False)
def section_frame(ub, a0, a1):
    """The bore's section in 2D: unit f, g = u_b x f across the bore (f along a0 where the
    journal is off centre) and a0, a1 in them: (f, g, a0_f, a0_g, a1_f, a1_g)."""
    size = math.sqrt(dot(a0, a0))
    f = scaled(a0, 1.0 / size) if size > 0.0 else vectors.perpendicular(ub)
    g = cross(ub, f)
    return f, g, dot(a0, f), dot(a0, g), dot(a1, f), dot(a1, g)


@numba.njit(cache=True, _nrt=False)
def sliced_depth_3d(states, contacts, k, z):
    """The deepest slice with the bore unmoved. Across the bore the journal's axis is off by
    |a0 + z' a1|, convex in z', so the deepest slice is an end slice: two are looked at,
    whatever the slicing."""
    pj, uj, _, a0, a1 = bore_section(states, contacts, k, z)
    zz = end_offset(contacts, k)
    plus, minus = add(a0, scaled(a1, zz)), sub(a0, scaled(a1, zz))
    if dot(minus, minus) > dot(plus, plus):
        zz, plus = -zz, minus
    size = math.sqrt(dot(plus, plus))
    n = scaled(plus, 1.0 / size) if size > 0.0 else (1.0, 0.0, 0.0)
    x = add(pj, scaled(uj, zz))
    return Depth(size - contacts[k, CONTACT_CLEARANCE], slice_rate(states, contacts, k, n, x, sub(x, plus)))


@numba.njit(cache=True, _nrt=False)
def sliced_forces_3d(force, y, dy, states, contacts, offsets, speeds, tables_, grid_log0, grid_step,
                     k, apply):
    """A journal along its bore, cut into n slices (pinbore.laws.sliced.slice_geometry: offset
    z_i from the mid-plane, weight w_i = L/n + e at each end slice). At slice i the journal's
    axis point X_i = P_j + z_i u_j has the eccentricity e_i = X_i - P_b - z_i u_b; across the
    bore it has length |e_i^perp|, normal n_i and penetration delta_i = |e_i^perp| - c. A
    journal tilted by theta in the plane of its eccentricity gives exactly delta_i = (e0 - c)
    + sin(theta) z_i: the sliced law with its small-angle tilt read as sin(theta). Each slice
    carries a f_el(delta_i) (1 + chi delta_i'/v0) w_i, a the law's stiffness factor, f_el the
    per-length law (N/m). The force -f n_i acts on the journal at X_i and +f n_i on the bore at
    B_i = X_i - e_i^perp, its point on the bore's axis: delta_i' = n_i . (v_J(X_i) - v_B(B_i))
    exactly, so the forces do the work of the law, and X_i - B_i is along n_i, so the pair has
    no moment; friction acts at C_i = B_i + R_b n_i. Bulk compliance (a sliced law with c_b >
    0): the slices carry the law's local part and the bore's axis moves across by d, the root
    of d = c_b F(d)/L with F the slices' resultant (laws.sliced.bore_displacement, in the
    bore's section); the slices then see e_i^perp - d, act at B_i = X_i - (e_i^perp - d) on the
    bore, and their rate is taken at fixed d. The deepest slice is an end slice (sliced_depth):
    a journal whose end slices are free skips the slices. Returns (normal force N, dissipated
    power W, the slices' friction forces' sizes summed N; NaN beyond the law's table). apply = False: the forces are not pushed, only the
    Iwan sliders of the slices held to their strength (after a step)."""
    z = (0.0, 0.0, 0.0)
    normal = power = tangential = 0.0
    pj, uj, ub, a0, a1 = bore_section(states, contacts, k, z)
    zz = end_offset(contacts, k)
    plus, minus = add(a0, scaled(a1, zz)), sub(a0, scaled(a1, zz))
    clearance = contacts[k, CONTACT_CLEARANCE]
    if max(dot(plus, plus), dot(minus, minus)) <= clearance * clearance:
        return normal, power, tangential
    table = tables_[int(contacts[k, CONTACT_TABLE])]
    f, g, ax, ay, bx, by = section_frame(ub, a0, a1)
    length, slices, scale = contacts[k, CONTACT_LENGTH], int(contacts[k, CONTACT_SLICES]), contacts[k, CONTACT_SCALE]
    dx, dy_ = sliced.bore_displacement(ax, ay, bx, by, clearance, False, length, slices, grid_log0,
                                       grid_step, table, 0.0, 0.0, contacts[k, CONTACT_END_LENGTH],
                                       scale, contacts[k, CONTACT_COMPLIANCE])
    if not math.isfinite(dx):
        return math.nan, math.nan, math.nan
    bb, bj = int(contacts[k, CONTACT_BEARING_BODY]), int(contacts[k, CONTACT_JOURNAL_BODY])
    speed = speeds[k]
    chi = contact_chi(contacts, k, speed)
    index = int(contacts[k, CONTACT_STATE])
    law = int(contacts[k, CONTACT_FRICTION_LAW])
    per_slice = 0 if index < 0 else (6 if law == IWAN else 3)
    total = length + 2.0 * contacts[k, CONTACT_END_LENGTH]   # the slices' weights summed
    for i in range(slices):
        offset, approach, nx, ny, _, f_loc, _ = sliced.slice_contact(
            i, dx, dy_, ax, ay, bx, by, clearance, False, length, slices, grid_log0, grid_step,
            table, 0.0, 0.0)
        if approach <= 0.0:
            continue
        weight = sliced.slice_geometry(i, length, slices, contacts[k, CONTACT_END_LENGTH])[2]
        n = add(scaled(f, nx), scaled(g, ny))
        x = add(pj, scaled(uj, offset))
        b = sub(x, scaled(n, approach + clearance))   # the bore's (moved) axis
        f_el = scale * weight * f_loc
        rate = slice_rate(states, contacts, k, n, x, b)
        f_n = dissipative.hysteresis_force(f_el, rate, speed, chi)
        state = index + i * per_slice
        c = add(b, scaled(n, contacts[k, CONTACT_RADIUS]))
        if not apply:
            if law == IWAN:
                iwan_return(states, contacts, k, f_n, n, y, state, weight / total)
            continue
        push(force, states, bj, scaled(n, -f_n), x, offsets)
        push(force, states, bb, scaled(n, f_n), b, offsets)
        p = (f_n - f_el) * rate
        if law != NO_FRICTION:
            v = sub(material_velocity(states, bj, c), material_velocity(states, bb, c))
            spin = (0.0, 0.0, 0.0)
            if law > LINEAR:   # a state follows the slice's normal: its turn across the bore
                w = sub(material_velocity(states, bj, x), material_velocity(states, bb, x))
                w = sub(w, add(scaled(n, dot(n, w)), scaled(ub, dot(ub, w))))
                spin = scaled(w, 1.0 / (approach + clearance))
            f_t, p_t, size = spatial_friction(states, contacts, k, f_n, n, v, y, dy, state, spin,
                                              weight / total)
            tangential += size
            if p_t != 0.0 or dot(f_t, f_t) > 0.0:
                push(force, states, bj, f_t, c, offsets)
                push(force, states, bb, negated(f_t), c, offsets)
                p += p_t
        normal += f_n
        power += p
    return normal, power, tangential


def sliced_depth(states, contacts, k, z):
    """sliced_depth_3d in space; no SLICED contact exists in the plane."""


@overload(sliced_depth, jit_options={"_nrt": False})
def _sliced_depth(states, contacts, k, z):
    if _space(z):
        return lambda states, contacts, k, z: sliced_depth_3d(states, contacts, k, z)
    if _plane(z):
        return lambda states, contacts, k, z: Depth(-math.inf, 0.0)


def sliced_forces(force, y, dy, states, contacts, offsets, speeds, tables_, grid_log0, grid_step, k,
                  apply, like):
    """sliced_forces_3d in space; no SLICED contact exists in the plane."""


@overload(sliced_forces, jit_options={"_nrt": False})
def _sliced_forces(force, y, dy, states, contacts, offsets, speeds, tables_, grid_log0, grid_step, k,
                   apply, like):
    if _space(like):
        return lambda force, y, dy, states, contacts, offsets, speeds, tables_, grid_log0, grid_step, \
            k, apply, like: sliced_forces_3d(force, y, dy, states, contacts, offsets, speeds, tables_,
                                             grid_log0, grid_step, k, apply)
    if _plane(like):
        return lambda force, y, dy, states, contacts, offsets, speeds, tables_, grid_log0, grid_step, \
            k, apply, like: (0.0, 0.0, 0.0)


# ---- Iwan sliders
@numba.njit(cache=True, _nrt=False)
def planar_iwan_return(contacts, k, f_n, y, index):
    """laws.friction.iwan_return_map of a contact point's slider (a float)."""
    stretch = index + STATE_STRETCH
    held = friction.iwan_return_map(y[stretch], contacts[k, IWAN_K1], contacts[k, IWAN_MU] * f_n)
    if held != y[stretch]:
        y[stretch] = held
        return True
    return False


@numba.njit(cache=True, _nrt=False)
def spatial_iwan_return(states, contacts, k, f_n, n, y, index, share):
    """The slider of a contact point held to |k1 z| <= mu F_n on the size of the stretch's
    tangent part (a vector in the bearing body's frame; a slice's k1 its `share`)."""
    bb = int(contacts[k, CONTACT_BEARING_BODY])
    stretch = index + 3 * STATE_STRETCH
    z = turned(states, bb, (y[stretch], y[stretch + 1], y[stretch + 2]))
    tangential = sub(z, scaled(n, dot(z, n)))
    size = math.sqrt(dot(tangential, tangential))
    limit = contacts[k, IWAN_MU] * f_n / (share * contacts[k, IWAN_K1])
    if size <= limit:
        return False
    held = unturned(states, bb, scaled(tangential, limit / size))
    y[stretch], y[stretch + 1], y[stretch + 2] = held[0], held[1], held[2]
    return True


def iwan_return(states, contacts, k, f_n, n, y, index, share):
    """The Iwan slider of a contact point held to its strength after a step (planar_iwan_return,
    spatial_iwan_return by the dimension; `share`: a slice's part of k1); whether it moved."""


@overload(iwan_return, jit_options={"_nrt": False})
def _iwan_return(states, contacts, k, f_n, n, y, index, share):
    if _plane(n):
        return lambda states, contacts, k, f_n, n, y, index, share: planar_iwan_return(
            contacts, k, f_n, y, index)
    if _space(n):
        return lambda states, contacts, k, f_n, n, y, index, share: spatial_iwan_return(
            states, contacts, k, f_n, n, y, index, share)


# ---- torsion elements
@numba.njit(cache=True, _nrt=False)
def torsion_law(angle, rate, row, latched):
    """Torque (N m) of a torsion spring, stop or latch at a relative angle beyond its free
    angle (rad) and its rate, and the power its damper dissipates. A stop acts beyond its
    angle and only pushes; a latch, once reached (`latched`), holds both ways."""
    kind = int(row[TORSION_KIND])
    stiffness, damping = row[TORSION_STIFFNESS], row[TORSION_DAMPING]
    if kind == LATCH:
        if latched:
            return -stiffness * angle - damping * rate, damping * rate * rate
        return 0.0, 0.0
    if kind == STOP and angle <= 0.0:
        return 0.0, 0.0
    torque = -stiffness * angle - damping * rate
    if kind == STOP and torque > 0.0:   # a stop pushes, never pulls: its stored energy is lost
        return 0.0, -stiffness * angle * rate
    return torque, damping * rate * rate


@numba.njit(cache=True, _nrt=False)
def torsion_angle(states, torsion, r, z):
    """(angle beyond the free angle, rate) of torsion element r: the relative rotation of its
    body j about body i's axis."""
    angle, _, rate, _ = relative_rotation(
        states, int(torsion[r, TORSION_BODY_I]), int(torsion[r, TORSION_BODY_J]),
        cell(torsion, r, TORSION_S_I, z), cell(torsion, r, TORSION_S_J, z),
        cell(torsion, r, TORSION_A_I, z), cell(torsion, r, TORSION_B_J, z),
        cell(torsion, r, TORSION_C_I, z), torsion[r, TORSION_FREE_ANGLE], 0.0)
    return angle, rate


# ---- the right-hand side
@numba.njit(cache=True)
def workspace(args):
    """The buffers of the right-hand side (layout.Work), sized for every constraint row: the
    ideal joints, the drive and a held contact per impulse contact."""
    z = args.like
    nb, nc = args.masses.size, args.contacts.shape[0]
    columns = args.offsets[nb]
    fixed = constraint_count(args.primitives, z)
    m = fixed + nc
    row_bodies, first = constraint_pattern(args.primitives, m, z)
    return Work(np.zeros((nb, body_columns(z))), np.zeros(columns), np.zeros((m, columns)),
                np.zeros(m), np.zeros(m), np.zeros(m), np.zeros((m, m)), np.zeros(columns),
                np.zeros(max(nc, 1)), np.zeros(max(nc, 1)), np.zeros((m, columns)), row_bodies, first)


@numba.njit(cache=True, _nrt=False)
def contact_forces(force, y, dy, states, contacts, offsets, speeds, tables_, grid_log0, grid_step,
                   normal, friction, z):
    """Every contact's forces into `force` (continuous contacts: impulse contacts act between
    steps and as held rows); per contact its normal and friction forces into `normal` and
    `friction`; the power dissipated, summed joint by joint (NaN beyond a law's table)."""
    for k in range(normal.size):
        normal[k] = 0.0
        friction[k] = 0.0
    dissipation = 0.0
    joint_power = 0.0
    for k in range(contacts.shape[0]):
        if int(contacts[k, CONTACT_IMPACT]) == CONTINUOUS:
            if int(contacts[k, CONTACT_KIND]) == SLICED:
                f_n, p, f_t = sliced_forces(force, y, dy, states, contacts, offsets, speeds, tables_,
                                            grid_log0, grid_step, k, True, z)
                normal[k] = f_n
                friction[k] = f_t
            else:
                p = point_contact(force, y, dy, states, contacts, offsets, k, speeds[k], grid_log0,
                                  grid_step, tables_, normal, friction, z)
            if not math.isfinite(p):
                return math.nan
            joint_power += p
        if k + 1 == contacts.shape[0] or contacts[k + 1, CONTACT_JOINT] != contacts[k, CONTACT_JOINT]:
            dissipation += joint_power
            joint_power = 0.0
    return dissipation


@numba.njit(cache=True, _nrt=False)
def torsion_forces(force, states, torsion, latched, offsets, dissipation, z):
    """Every torsion element's torque into `force`; `dissipation` plus the power their dampers
    dissipate (added one by one, as the contacts' before them)."""
    for r in range(torsion.shape[0]):
        angle, rate = torsion_angle(states, torsion, r, z)
        torque, power = torsion_law(angle, rate, torsion[r], latched[r] > 0)
        s_i, s_j = cell(torsion, r, TORSION_S_I, z), cell(torsion, r, TORSION_S_J, z)
        u = rotation_axis(states, int(torsion[r, TORSION_BODY_I]), s_i, cell(torsion, r, TORSION_A_I, z),
                          cell(torsion, r, TORSION_C_I, z))
        push_torque(force, states, int(torsion[r, TORSION_BODY_J]), s_j, scaled(u, torque), offsets)
        push_torque(force, states, int(torsion[r, TORSION_BODY_I]), s_i, scaled(u, -torque), offsets)
        dissipation += power
    return dissipation


@numba.njit(cache=True, _nrt=False)
def spring_ends(states, springs, r, z):
    """Spring-damper r's two points (positions, velocities) and its length |s_j - s_i|."""
    x_i, v_i, _, _ = point_state(states, int(springs[r, SPRING_BODY_I]), cell(springs, r, SPRING_S_I, z))
    x_j, v_j, _, _ = point_state(states, int(springs[r, SPRING_BODY_J]), cell(springs, r, SPRING_S_J, z))
    return x_i, v_i, x_j, v_j, norm(sub(x_j, x_i))


@numba.njit(cache=True, _nrt=False)
def spring_forces(force, states, springs, offsets, dissipation, z):
    """Every linear spring-damper's force into `force`: the tension T = k (L - L0) + c L' pulls
    its two points together along the line n from s_i to s_j (-T n on body j, T n on body i);
    `dissipation` plus the damper's power c L'^2. Two points that coincide have no line: the
    element is idle there (L0 > 0 keeps them apart in any sensible scene)."""
    for r in range(springs.shape[0]):
        bi, bj = int(springs[r, SPRING_BODY_I]), int(springs[r, SPRING_BODY_J])
        x_i, v_i, x_j, v_j, length = spring_ends(states, springs, r, z)
        if length == 0.0:
            continue
        n = scaled(sub(x_j, x_i), 1.0 / length)
        rate = dot(n, sub(v_j, v_i))
        tension = springs[r, SPRING_STIFFNESS] * (length - springs[r, SPRING_LENGTH]) \
            + springs[r, SPRING_DAMPING] * rate
        push(force, states, bj, scaled(n, -tension), x_j, offsets)
        push(force, states, bi, scaled(n, tension), x_i, offsets)
        dissipation += springs[r, SPRING_DAMPING] * rate * rate
    return dissipation


@numba.njit(cache=True, _nrt=False)
def load_forces(t, force, states, velocities, loads, offsets, z):
    """Every harmonic load into `force`: F cos(w t + phi) at its body point and T cos(w t + phi)
    on the body's frame there (global amplitudes); returns their power, the generalised
    forces they add times the velocities of the same columns."""
    power = 0.0
    for r in range(loads.shape[0]):
        b = int(loads[r, LOAD_BODY])
        if b < 0:
            continue
        c = math.cos(loads[r, LOAD_OMEGA] * t + loads[r, LOAD_PHASE])
        s = cell(loads, r, LOAD_POINT, z)
        x = point_state(states, b, s)[0]
        for col in range(offsets[b], offsets[b + 1]):
            power -= force[col] * velocities[col]
        push(force, states, b, scaled(cell(loads, r, LOAD_FORCE, z), c), x, offsets)
        push_torque(force, states, b, s, angular_cell(loads, r, LOAD_TORQUE, c, z), offsets)
        for col in range(offsets[b], offsets[b + 1]):
            power += force[col] * velocities[col]
    return power


@numba.njit(cache=True, _nrt=False)
def constrained_forces(force, jac, mjac, rhs_c, phi_t, schur, row_bodies, first, offsets, m):
    """Solve (D M^-1 D^T) lambda = D M^-1 Q - gamma~ (gamma~ in rhs_c, lambda into it), take
    D^T lambda from the forces Q, and return the power of the constraint forces."""
    for i in range(m):
        v = -rhs_c[i]
        for side in range(2):
            b = row_bodies[i, side]
            if b >= 0:
                for c in range(offsets[b], offsets[b + 1]):
                    v += mjac[i, c] * force[c]
        rhs_c[i] = v
    cholesky_solve(schur, rhs_c, m, first)
    work_in = 0.0
    for i in range(m):   # Q - D^T lambda
        for side in range(2):
            b = row_bodies[i, side]
            if b >= 0:
                for c in range(offsets[b], offsets[b + 1]):
                    force[c] -= jac[i, c] * rhs_c[i]
        work_in += rhs_c[i] * phi_t[i]
    return work_in


@numba.njit(cache=True, _nrt=False)
def rhs(t, y, dy, args, work):
    """dy = f(t, y): the coordinates' rates and second derivatives, the dissipated power, the
    power of the constraints, the rates of the friction states. args: layout.Args; work:
    layout.Work. The bundles are opened once, here (numba counts the references of every
    array a function receives, and of every array in a bundle it receives)."""
    kind, z, nq = args.kind, args.like, args.nq
    masses, minv, inertia, offsets = args.masses, args.minv, args.inertia, args.offsets
    contacts, primitives, mode = args.contacts, args.primitives, args.mode
    states, force, normal, jac, mjac = work.bodies, work.force, work.normal, work.jac, work.mjac
    rhs_c, phi_t, row_bodies = work.rhs_c, work.phi_t, work.row_bodies
    body_states(kind, y, nq, args.inertia_inv, args.flex, offsets, states, work.velocities)
    damping = body_forces(kind, masses, minv, inertia, args.gravity, args.flex, states, force)
    for i in range(2 * nq + ENERGY_STATES, y.size):
        dy[i] = 0.0   # friction states rest out of contact
    dissipation = contact_forces(force, y, dy, states, contacts, offsets, args.speeds, args.tables,
                                 args.grid_log0, args.grid_step, normal, work.friction, z)
    if not math.isfinite(dissipation):
        for i in range(dy.size):   # penetration beyond the tabulated law: the integrator stops
            dy[i] = math.nan
        return
    dissipation = torsion_forces(force, states, args.torsion, args.latched, offsets, dissipation, z)
    dissipation = spring_forces(force, states, args.springs, offsets, dissipation, z)
    dissipation += damping
    loaded = load_forces(t, force, states, work.velocities, args.loads, offsets, z)
    m = constraint_rows(t, primitives, args.profile, contacts, mode, offsets, states, work.velocities, jac, mjac,
                        work.phi, phi_t, rhs_c, row_bodies, args.baumgarte, z)
    work_in = 0.0
    if m > 0:
        fill_schur(kind, masses, minv, offsets, states, jac, mjac, work.schur, row_bodies, work.first, m)
        work_in = constrained_forces(force, jac, mjac, rhs_c, phi_t, work.schur, row_bodies,
                                     work.first, offsets, m)
        row = m
        for k in range(contacts.shape[0]):
            row -= mode[k]
        for k in range(contacts.shape[0]):
            if mode[k] == 1:
                normal[k] = rhs_c[row]   # the multiplier of delta = 0 is the normal force
                row += 1
    state_rates(kind, y, dy, nq, masses, minv, args.baumgarte, states, force)
    dy[2 * nq + DISSIPATED] = dissipation
    dy[2 * nq + WORK_IN] = work_in + loaded


@numba.njit(cache=True)
def constraint_values(t, y, args):
    """(Phi_q, Phi, Phi_t) of the ideal joints and the drive (and held contacts) at the
    positions of y, as new arrays (Python-side: the kinds' projections)."""
    work = workspace(args)
    refresh(y, args, work)
    m = fill_constraints(t, args, work, 0.0)
    return work.jac[:m].copy(), work.phi[:m].copy(), work.phi_t[:m].copy()


def rhs_value(t, y, args):
    """(f(t, y), normal force per contact) as new arrays (Python-side convenience)."""
    dy, work = integrator.evaluate_once(workspace, rhs, t, y, args)
    return dy, work.normal[:args.contacts.shape[0]].copy()


# ---- what the outputs see of a state
@numba.njit(cache=True)
def observe(t, y, dy, args, work, depth, offset):
    """One state as the outputs see it: f(t, y) into dy, each contact's normal and friction
    forces into work.normal and work.friction (rhs), its deepest penetration into depth and
    its journal point's offset from its bearing point (global) into offset[k], the body
    states into work.bodies; returns the ideal joints' largest gap |Phi| (no held contacts)."""
    z = args.like
    rhs(t, y, dy, args, work)
    states = work.bodies
    contacts = args.contacts
    for k in range(contacts.shape[0]):
        depth[k] = contact_depth(states, contacts, k, z).delta
        e = sub(point_state(states, int(contacts[k, CONTACT_JOURNAL_BODY]),
                            cell(contacts, k, CONTACT_JOURNAL_POINT, z))[0],
                point_state(states, int(contacts[k, CONTACT_BEARING_BODY]),
                            cell(contacts, k, CONTACT_BEARING_POINT, z))[0])
        for i in range(len(z)):
            offset[k, i] = e[i]
    m = constraint_rows(t, args.primitives, args.profile, contacts, args.mode * 0, args.offsets, states,
                        work.velocities, work.jac, work.mjac, work.phi, work.phi_t, work.rhs_c,
                        work.row_bodies, 0.0, z)
    gap = 0.0
    for i in range(m):
        gap = max(gap, abs(work.phi[i]))
    return gap


@numba.njit(cache=True)
def observe_steps(times, states, speeds, latched, modes, args, work, rates, bodies, depths,
                  normals, frictions, offsets, drift, kinetic, angles, stretches):
    """observe, energy_of, torsion_angles and spring_lengths at every recorded step (row k of
    times, states, and of the impact speeds, latch flags and contact modes the step was taken
    with, which go into args in place), into the rows of the output arrays: the outputs' one
    pass over a run in compiled code (a Python loop over the steps cost ten times the
    integration of a short run)."""
    nc, nt = args.speeds.shape[0], args.latched.shape[0]
    kept = bodies.shape[2]
    dy = np.empty(states.shape[1])
    depth, offset = np.empty(nc), np.zeros((nc, offsets.shape[2]))
    angle, stretch = np.empty(nt), np.empty(args.springs.shape[0])
    for k in range(times.size):
        args.speeds[:] = speeds[k, :nc]
        args.latched[:] = latched[k, :nt]
        for i in range(nc):
            args.mode[i] = modes[k, i]
        drift[k] = observe(times[k], states[k], dy, args, work, depth, offset)
        rates[k] = dy
        bodies[k] = work.bodies[:, :kept]
        depths[k], offsets[k] = depth, offset
        normals[k], frictions[k] = work.normal[:nc], work.friction[:nc]
        kinetic[k] = energy_of(states[k], args)
        torsion_angles(states[k], args, work, angle)
        angles[k] = angle
        spring_lengths(states[k], args, work, stretch)
        stretches[k] = stretch


@numba.njit(cache=True)
def relative_motion(y, args, work, bb, s_b, bj, s_j, f, g):
    """Body bj's point s_j relative to body bb's point s_b (body frames): the offset e and the
    relative velocity v_j(P_j) - v_b(P_j) along body bb's vectors f and g (its frame; the
    ground's: global), (e.f, e.g, v.f, v.g)."""
    refresh(y, args, work)
    states = work.bodies
    pj = point_state(states, bj, s_j)[0]
    e = sub(pj, point_state(states, bb, s_b)[0])
    v = sub(material_velocity(states, bj, pj), material_velocity(states, bb, pj))
    ff, gg = vector_state(states, bb, s_b, f)[0], vector_state(states, bb, s_b, g)[0]
    return dot(e, ff), dot(e, gg), dot(v, ff), dot(v, gg)


@numba.njit(cache=True)
def torsion_angles(y, args, work, angles):
    """Each torsion element's angle beyond its free angle into `angles` (rad)."""
    refresh(y, args, work)
    for r in range(args.torsion.shape[0]):
        angles[r] = torsion_angle(work.bodies, args.torsion, r, args.like)[0]


@numba.njit(cache=True)
def spring_lengths(y, args, work, lengths):
    """Each spring-damper's length L beyond its free length L0 into `lengths` (m)."""
    refresh(y, args, work)
    for r in range(args.springs.shape[0]):
        lengths[r] = spring_ends(work.bodies, args.springs, r, args.like)[4] - args.springs[r, SPRING_LENGTH]


@numba.njit(cache=True)
def slice_approaches(y, args, work, k, approaches, weights):
    """The slices of SLICED contact k with the bore moved by its bulk compliance
    (laws.sliced.bore_displacement; 0 without): each slice's approach delta_i into
    `approaches` (m), its weight a w_i into `weights` (m); returns the bore's displacement
    (global; NaN beyond the law's table). For the energy book of the outputs."""
    z = args.like
    refresh(y, args, work)
    contacts = args.contacts
    _, _, ub, a0, a1 = bore_section(work.bodies, contacts, k, z)
    f, g, ax, ay, bx, by = section_frame(ub, a0, a1)
    length, slices = contacts[k, CONTACT_LENGTH], int(contacts[k, CONTACT_SLICES])
    clearance, table = contacts[k, CONTACT_CLEARANCE], args.tables[int(contacts[k, CONTACT_TABLE])]
    dx, dy = sliced.bore_displacement(ax, ay, bx, by, clearance, False, length, slices,
                                      args.grid_log0, args.grid_step, table, 0.0, 0.0,
                                      contacts[k, CONTACT_END_LENGTH], contacts[k, CONTACT_SCALE],
                                      contacts[k, CONTACT_COMPLIANCE])
    for i in range(slices):
        approaches[i] = sliced.slice_contact(i, dx, dy, ax, ay, bx, by, clearance, False, length,
                                             slices, args.grid_log0, args.grid_step, table, 0.0, 0.0)[1]
        weights[i] = contacts[k, CONTACT_SCALE] * sliced.slice_geometry(
            i, length, slices, contacts[k, CONTACT_END_LENGTH])[2]
    return add(scaled(f, dx), scaled(g, dy))


# ---- impacts and the projection onto the constraints
@numba.njit(cache=True, _nrt=False)
def refresh(y, args, work):
    """The body states of y into the workspace."""
    body_states(args.kind, y, args.nq, args.inertia_inv, args.flex, args.offsets, work.bodies,
                work.velocities)


@numba.njit(cache=True, _nrt=False)
def fill_constraints(t, args, work, alpha):
    """Jacobian D, Phi, Phi_t and gamma - 2 a Phi' - a^2 Phi into the workspace (body states
    current) for the ideal joints, the drive and the held contacts; the number of rows."""
    return constraint_rows(t, args.primitives, args.profile, args.contacts, args.mode, args.offsets, work.bodies,
                           work.velocities, work.jac, work.mjac, work.phi, work.phi_t, work.rhs_c,
                           work.row_bodies, alpha, args.like)


@numba.njit(cache=True, _nrt=False)
def solve_rows(args, work, m):
    """(D M^-1 D^T) x = b in place in work.rhs_c[:m]."""
    fill_schur(args.kind, args.masses, args.minv, args.offsets, work.bodies, work.jac, work.mjac,
               work.schur, work.row_bodies, work.first, m)
    cholesky_solve(work.schur, work.rhs_c, m, work.first)


@numba.njit(cache=True, _nrt=False)
def energy_of(y, args):
    return kinetic_energy(args.kind, y, args.nq, args.masses, args.minv, args.inertia, args.flex,
                          args.offsets)


@numba.njit(cache=True, _nrt=False)
def step_velocities(y, args, work, m, scale):
    velocity_step(args.kind, y, args.nq, args.minv, work.jac, work.mjac, work.rhs_c, work.bodies, m,
                  scale)


@numba.njit(cache=True, _nrt=False)
def apply_impulse(t, y, args, work, k, target_restitution):
    """Impact of impulse contact k (approaching at delta' = v > 0): the velocity jump of least
    kinetic-energy change that keeps every ideal joint and held contact and leaves the
    contact's approach rate at -e v, i.e. v+ = v - M^-1 G^T (G M^-1 G^T)^-1 (G v - b) with G the
    constraint rows plus the contact's normal. Newton's hypothesis sets e on velocities
    directly; Poisson's applies the compression impulse P_c (rate to 0) and then e P_c. For a
    frictionless impact the two coincide (the normal rate is linear in the impulse).
    Returns the layout.Impulse: normal impulse on the journal (N s), energy dissipated (J),
    work of the drive's impulse (J)."""
    z = args.like
    contacts, mode = args.contacts, args.mode
    rhs_c, phi_t = work.rhs_c, work.phi_t
    refresh(y, args, work)
    rate = contact_depth(work.bodies, contacts, k, z).rate
    before = energy_of(y, args)
    held = mode[k]
    mode[k] = 1
    m = fill_constraints(t, args, work, 0.0)
    mode[k] = held
    row = constraint_count(args.primitives, z)
    for j in range(k):
        row += mode[j]
    poisson = int(contacts[k, CONTACT_IMPACT]) == POISSON
    e = target_restitution
    for i in range(m):
        rhs_c[i] = 0.0
    rhs_c[row] = rate if poisson else (1.0 + e) * rate
    solve_rows(args, work, m)
    scale = (1.0 + e) if poisson else 1.0
    step_velocities(y, args, work, m, scale)
    after = energy_of(y, args)
    work_in = 0.0   # the drive's impulse works on its prescribed speed
    for i in range(m):
        work_in += scale * rhs_c[i] * phi_t[i]
    return Impulse(scale * rhs_c[row], before - after + work_in, work_in)


@numba.njit(cache=True, _nrt=False)
def project_onto_constraints(t, y, args, work, tolerance, rate_tolerance):
    """The coordinates normalised (bodies.normalise); then one Gauss-Newton step of positions
    and one of velocities onto Phi = 0 and D v + Phi_t = 0 (ideal joints, drive, held
    contacts), least change in the mass metric (dx = -M^-1 D^T (D M^-1 D^T)^-1 Phi), each only
    where the residual exceeds its tolerance (m, m/s). Keeps the drift of accepted steps from
    accumulating where Baumgarte alone is too slow (loose tolerances, fast drives). Returns
    whether a constraint was projected; the body states of y are in the workspace either way."""
    z = args.like
    rhs_c = work.rhs_c
    normalise(args.kind, y, args.nq, args.offsets)
    changed = False
    m = 0
    for level in range(2):
        if level == 0 or changed:   # positions unmoved: the Jacobian of level 0 holds
            refresh(y, args, work)
            m = fill_constraints(t, args, work, 0.0)
        largest = 0.0
        for i in range(m):
            if level == 0:
                rhs_c[i] = work.phi[i]
            else:
                rhs_c[i] = constraint_rate(work.jac, work.phi_t, work.row_bodies, work.bodies,
                                           work.velocities, i, args.offsets, z)
            largest = max(largest, abs(rhs_c[i]))
        if largest <= (tolerance if level == 0 else rate_tolerance):
            continue
        changed = True
        solve_rows(args, work, m)
        if level == 0:
            position_step(args.kind, y, args.nq, args.minv, work.jac, work.mjac, rhs_c, work.bodies, m)
        else:
            step_velocities(y, args, work, m, 1.0)
    if changed:
        refresh(y, args, work)
    return changed


@numba.njit(cache=True, _nrt=False)
def impulse_energy(y, nq, impulse):
    """Book an impulse's dissipation and drive work in the energy states; the impulse."""
    y[2 * nq + DISSIPATED] += impulse.dissipated
    y[2 * nq + WORK_IN] += impulse.work_in
    return impulse.impulse


# ---- the integrator's hooks
@numba.njit(cache=True, _nrt=False)
def engage_latches(states, torsion, latched, z):
    """Latch every latch that has reached its angle (to within LATCH_TOL; body states
    current). Returns whether one engaged."""
    changed = False
    for r in range(torsion.shape[0]):
        if latched[r] == 0.0 and int(torsion[r, TORSION_KIND]) == LATCH and \
                torsion_angle(states, torsion, r, z)[0] > -LATCH_TOL:
            latched[r] = 1.0
            changed = True
    return changed


@numba.njit(cache=True)
def start(y, args, onset_tol):
    """The contact state at t = 0 (latches given as engaged engage), what this mechanism needs
    checked: (impulse contacts, Iwan elements, latches), and a buffer for one step's onsets
    (at most one a contact)."""
    z = args.like
    contacts, torsion = args.contacts, args.torsion
    nc = contacts.shape[0]
    impulse_contacts = iwan = latches = False
    for k in range(nc):
        impulse_contacts |= int(contacts[k, CONTACT_IMPACT]) != CONTINUOUS
        iwan |= int(contacts[k, CONTACT_FRICTION_LAW]) == IWAN
    for r in range(torsion.shape[0]):
        latches |= int(torsion[r, TORSION_KIND]) == LATCH
    work = workspace(args)
    refresh(y, args, work)
    engage_latches(work.bodies, torsion, args.latched, z)   # a latch given as engaged stays so
    tracked = Contacts(np.zeros(nc), np.zeros(nc, np.bool_), np.zeros(nc), np.zeros(nc))
    for k in range(nc):
        tracked.depth[k] = contact_depth(work.bodies, contacts, k, z).delta
        tracked.in_contact[k] = (tracked.depth[k] > -onset_tol
                                 and int(contacts[k, CONTACT_IMPACT]) == CONTINUOUS)
    return tracked, (impulse_contacts, iwan, latches), np.empty((max(nc, 1), LOG_COLUMNS))


@numba.njit(cache=True, _nrt=False)
def onset_fraction(states, contacts, mode, depth, in_contact, onset_tol, z):
    """Event location: the fraction of a trial step (its end's body states) that ends it at
    the first onset of a free contact (integrator.onset_shortening). 1: none."""
    shorten = 1.0
    for k in range(contacts.shape[0]):
        if not in_contact[k] and mode[k] == 0:
            d_new = contact_depth(states, contacts, k, z).delta
            shorten = min(shorten, integrator.onset_shortening(depth[k], d_new, onset_tol))
    return shorten


@numba.njit(cache=True, _nrt=False)
def release_fraction(mode, normal, held_force, held_peak, rtol):
    """Event location: the fraction of a trial step that ends it where a held contact's force
    (normal: at the step's end, the last rhs evaluation's multipliers) turns pulling, by a
    secant on the force. 1: no release."""
    shorten = 1.0
    for k in range(mode.size):
        if mode[k] == 1:
            f_new = normal[k]
            if held_force[k] > 0.0 and f_new < -1e-3 * math.sqrt(rtol) * held_peak[k]:
                shorten = min(shorten, 0.99 * held_force[k] / (held_force[k] - f_new))
    return shorten


@numba.njit(cache=True, _nrt=False)
def event_fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt):
    """Event location: the fraction of a trial step that ends it at its first event: the
    onset of a free contact, the zero of a held contact's force, a latch reaching its angle
    (secant on the angle). 1: none."""
    z = args.like
    torsion, latched = args.torsion, args.latched
    states = work.bodies
    refresh(y_new, args, work)
    tracked = contacts   # the integrator's name for the contact tracking (layout.Contacts)
    shorten = onset_fraction(states, args.contacts, args.mode, tracked.depth, tracked.in_contact,
                             onset_tol, z)
    if needs[0] and h > event_dt:
        shorten = min(shorten, release_fraction(args.mode, work.normal, tracked.held_force,
                                                tracked.held_peak, rtol))
    if needs[2]:
        for r in range(torsion.shape[0]):
            if latched[r] == 0.0 and int(torsion[r, TORSION_KIND]) == LATCH:
                a_new = torsion_angle(states, torsion, r, z)[0]
                if a_new > LATCH_TOL:   # the angle at the step's start, then back to its end
                    refresh(y, args, work)
                    a_old = torsion_angle(states, torsion, r, z)[0]
                    refresh(y_new, args, work)
                    shorten = min(shorten, 0.99 * (-a_old) / (a_new - a_old))
    return shorten


@numba.njit(cache=True, _nrt=False)
def release_held_contacts(t, y, args, work, tracked):
    """Accepted step: the held contacts' forces (the multipliers at the step's end); one that
    pulls releases, and an approach rate left by drift is removed (an impulse with e = 0).
    Returns whether a contact was released."""
    z = args.like
    contacts, mode, normal, nq = args.contacts, args.mode, work.normal, args.nq
    changed = False
    for k in range(contacts.shape[0]):
        if mode[k] == 1:
            tracked.held_force[k] = normal[k]
            tracked.held_peak[k] = max(tracked.held_peak[k], tracked.held_force[k])
            if tracked.held_force[k] < 0.0:   # released; an approach rate left by drift is removed
                refresh(y, args, work)
                if contact_depth(work.bodies, contacts, k, z).rate > 0.0:
                    impulse_energy(y, nq, apply_impulse(t, y, args, work, k, 0.0))
                mode[k] = 0
                changed = True
    return changed


@numba.njit(cache=True, _nrt=False)
def onsets_and_impacts(t, y, args, work, tracked, onset_tol, speed_floor, events):
    """Accepted step, per contact: the penetration; an impulse contact arriving (approaching
    within onset_tol) takes its impact, and one too slow to rebound is held; a continuous
    contact arriving records its impact speed v0 (at least speed_floor) and restarts its Iwan
    elements unloaded; one that left contact is marked free. Every impact and onset goes into
    `events` (layout.LOG_*). Returns (whether anything happened, the number of events)."""
    z = args.like
    contacts, mode, speeds, nq = args.contacts, args.mode, args.speeds, args.nq
    depth, in_contact = tracked.depth, tracked.in_contact
    states = work.bodies
    changed = False
    current = False
    arrived = 0
    for k in range(contacts.shape[0]):
        if not current:
            refresh(y, args, work)
            current = True
        d = contact_depth(states, contacts, k, z)
        delta, rate = d.delta, d.rate
        depth[k] = delta
        onset, impulse = False, 0.0
        if int(contacts[k, CONTACT_IMPACT]) != CONTINUOUS:
            if mode[k] == 0 and delta > -onset_tol and rate > 0.0:
                restitution = contacts[k, CONTACT_RESTITUTION]
                e = restitution if restitution * rate >= contacts[k, CONTACT_REST_SPEED] else 0.0
                impulse = impulse_energy(y, nq, apply_impulse(t, y, args, work, k, e))
                current = False
                if e == 0.0:   # too slow to rebound: held contact (the third state)
                    mode[k] = 1
                    tracked.held_force[k] = tracked.held_peak[k] = 0.0
                speeds[k] = rate
                onset = True
        elif not in_contact[k] and delta > -onset_tol:
            in_contact[k] = True
            speeds[k] = max(rate, speed_floor)
            if int(contacts[k, CONTACT_FRICTION_LAW]) == IWAN:   # a new contact point: unloaded
                index = int(contacts[k, CONTACT_STATE])
                for i in range(index, index + iwan_states(contacts, k, z)):
                    y[i] = 0.0
            onset = True
        elif in_contact[k] and delta < -onset_tol:
            in_contact[k] = False
        if onset:
            changed = True
            events[arrived, LOG_TIME], events[arrived, LOG_JOINT] = t, contacts[k, CONTACT_JOINT]
            events[arrived, LOG_RATE], events[arrived, LOG_IMPULSE] = rate, impulse
            arrived += 1
    return changed, arrived


@numba.njit(cache=True, _nrt=False)
def iwan_states(contacts, k, z):
    """The number of friction states of an Iwan contact: travel and stretch per point (a
    float each in the plane, a vector in space), per slice of a SLICED one."""
    per_point = 2 if len(z) == 2 else 6
    if int(contacts[k, CONTACT_KIND]) == SLICED:
        return per_point * int(contacts[k, CONTACT_SLICES])
    return per_point


@numba.njit(cache=True, _nrt=False)
def iwan_slider_return(y, args, work, tracked):
    """Accepted step: the Iwan slider of every contact in contact held to |k1 z| <= mu F_n at
    the accepted state. Returns whether a slider moved."""
    z = args.like
    contacts, speeds = args.contacts, args.speeds
    refresh(y, args, work)
    states = work.bodies
    changed = False
    for k in range(contacts.shape[0]):
        if int(contacts[k, CONTACT_FRICTION_LAW]) != IWAN or not tracked.in_contact[k]:
            continue
        if int(contacts[k, CONTACT_KIND]) == SLICED:
            sliced_forces(work.force, y, y, states, contacts, args.offsets, speeds, args.tables,
                          args.grid_log0, args.grid_step, k, False, z)
            continue
        if int(contacts[k, CONTACT_KIND]) == PLANE:
            p = plane_geometry(states, contacts, k, z)
            delta, n, rate = p.delta, p.normal, p.rate
        else:
            g = radial_geometry(states, contacts, k, z)
            delta, n, rate = g.delta, g.normal, g.rate
        f_n = 0.0   # open (within the onset tolerance): the slider holds nothing
        if delta > 0.0:
            f_el = elastic_force(contacts, k, delta, args.grid_log0, args.grid_step, args.tables)
            f_n = dissipative.hysteresis_force(f_el, rate, speeds[k], contact_chi(contacts, k, speeds[k]))
        changed |= iwan_return(states, contacts, k, f_n, n, y, int(contacts[k, CONTACT_STATE]), 1.0)
    return changed


@numba.njit(cache=True, _nrt=False)
def after_step(t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, events):
    """The updates of an accepted step: held contacts released, onsets and impacts, Iwan
    sliders held, latches engaged; and the coordinates normalised and, where they drifted,
    projected onto the constraints, before the events or after them (layout.Args:
    project_first). Returns (whether y or the laws' state changed, the number of onsets and
    impacts written into `events`)."""
    tracked = contacts   # the integrator's name for the contact tracking (layout.Contacts)
    projected = args.project_first and project_onto_constraints(t, y, args, work, onset_tol, rate_tol)
    released = needs[0] and release_held_contacts(t, y, args, work, tracked)
    happened, arrived = onsets_and_impacts(t, y, args, work, tracked, onset_tol, speed_floor, events)
    slid = needs[1] and iwan_slider_return(y, args, work, tracked)
    engaged = False
    if needs[2]:
        refresh(y, args, work)
        engaged = engage_latches(work.bodies, args.torsion, args.latched, args.like)
    if not args.project_first:
        projected = project_onto_constraints(t, y, args, work, onset_tol, rate_tol)
    return projected or released or happened or slid or engaged, arrived


def mechanism(args) -> bool:
    return getattr(args, "instance_class", None) is layout.Args


@overload(integrator.new_workspace, inline="always")
def _new_workspace(args):
    if mechanism(args):
        return lambda args: workspace(args)


@overload(integrator.evaluate, inline="always")
def _evaluate(t, y, dy, args, work):
    if mechanism(args):
        return rhs.py_func


@overload(integrator.start)   # not inlined: numba's inliner loses the branches of its loop
def _start(y, args, onset_tol):
    if mechanism(args):
        return start.py_func


# (compiled apart and without the reference-counting runtime: inlined into the integrator's
# loop, which allocates and so keeps it, their bundles' arrays would be counted at every step)
@overload(integrator.event_fraction, jit_options={"_nrt": False})
def _event_fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt):
    if mechanism(args):
        return event_fraction.py_func


@overload(integrator.after_step, jit_options={"_nrt": False})
def _after_step(t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, events):
    if mechanism(args):
        return after_step.py_func


integrate = integrator.integrate

# ---- the compiled code follows what it compiles in: the laws, the layout, the vectors, the
# body kinds' implementations of reduced.mechanism.bodies (numba's cache checks only the file
# a function is defined in; pinbore.core.compiled drops this module's cache when these change)
COMPILED_IN = (friction.__file__, dissipative.__file__, tables.__file__, sliced.__file__,
               *beside(__file__, "layout", "vectors", "bodies", "linalg", "integrator", "planar", "spatial"))
follow_compiled_in(globals(), COMPILED_IN)
