r"""The compiled core of the reduced model: equations of motion and the integrator.

Planar rigid bodies with coordinates q = (x_k, y_k, phi_k) of their centres of mass,
M = diag(m_k, m_k, J_k). Ideal joints and the drive are constraints Phi(q, t) = 0 with
Lagrange multipliers ([Cao2013] eq. 21; stabilised after [Baumgarte1972]):

    M q'' + Phi_q^T lambda = Q(q, q', t),
    Phi_q q''  = gamma - 2 a Phi' - a^2 Phi          (Baumgarte, a the stabilisation rate).

M is diagonal, so lambda comes from the small Schur system (Phi_q M^-1 Phi_q^T) lambda =
Phi_q M^-1 Q - gamma~. Revolute joints Phi = r_i + A_i s_i - r_j - A_j s_j, prismatic joints
n.(r + A s - P) = 0 and phi = phi_0, the drive phi = phi_0 + omega t.

A revolute clearance joint is no constraint: the journal centre P_j moves inside the bearing
(centre P_b, radius R_b, clearance c = R_b - R_j). With e = P_j - P_b, the penetration is
delta = |e| - c, the normal n = e/|e|, the contact point P_b + R_b n. Continuous contact: while
delta > 0 the normal force is F_n = F_el(delta) (1 + chi delta'/v0)  (>= 0), F_el from a
table of the elastic law (pinbore.laws.tables: log-log interpolation, exact for a power law), chi the hysteresis
factor of the damping law, v0 the approach rate at the onset of this impact; the friction
force opposes the tangential slip v_t: Ambrosio's regularised Coulomb, polynomial Stribeck or
a linear velocity law (static, regularised near zero slip), LuGre or Dahl normalised by F_n,
or the bilinear Iwan element, whose states are integrated with the motion (and rest while
the joint is open). The normal force and every friction law are the functions of
pinbore.laws.dissipative and pinbore.laws.friction, compiled into the right-hand side. While
delta <= 0 no law is evaluated. Impulse contact (Newton or Poisson): rigid impacts between
steps (apply_impulse) and, below a rest speed, held contact: the constraint delta = 0 joins
the ideal ones until its multiplier (the normal force) would pull.

Extra states integrate the energy dissipated in the joints and the work of the constraint
forces (the drive), so the energy balance can be checked.

Integrators: reduced.integrator (DOPRI5 with event location, Rosenbrock 2(3), fixed-step
DOPRI5), written once for the planar and the spatial mechanisms; this kernel overloads its
hooks for KernelArgs. A step ends at its first event (onset_fraction, release_fraction,
latch_fraction): a step that would carry a joint from free flight into contact deeper than
`onset_tol` is shortened (secant on delta) until it ends at the onset, where v0 is recorded,
so every impact starts on a step boundary with a known impact speed; latches engage the same
way, at their angle, so their spring starts unloaded, and held contacts release at the zero
of their force. The accepted step's updates (release_held_contacts, onsets_and_impacts with
the impact log, iwan_slider_return, engage_latches) come then, and, where the drift exceeds
the onset tolerance, the projection of positions and velocities back onto the constraints
(project_onto_constraints: one mass-weighted Gauss-Newton step each), so drift cannot
accumulate where Baumgarte alone is too slow.
The row arrays and argument bundles are laid out in reduced.layout. numba counts the
references of every array a compiled function receives or reads out of a bundle (an atomic
increment and decrement each), about half the run time of the slider-crank: so a
function reads the fields it uses once, at its top, and the helpers that run at every step
take the arrays they use rather than whole bundles. The right-hand side works in
preallocated buffers and solves the Schur system by Cholesky: about 1.2 us per evaluation
for the slider-crank.
"""

import math

import numba
import numpy as np

from numba.extending import overload

from pinbore.core.compiled import follow_compiled_in
from pinbore.laws import dissipative, friction, tables
from pinbore.reduced import integrator, layout
from pinbore.reduced.integrator import (  # noqa: F401 (the status and method codes, re-exported)
    BLOWN_UP, DOPRI5, DOPRI5_FIXED, OK, ROSENBROCK23, STEP_TOO_SMALL, TOO_MANY_STEPS, integrate, log_impact)
from pinbore.reduced.layout import (
    CONTINUOUS, COULOMB, COULOMB_MU, DAHL_MU, DAHL_SIGMA, DISSIPATED, DRIVE_ANGLE, DRIVE_BODY,
    DRIVE_SPEED, ENERGY_STATES, IWAN, IWAN_K1, IWAN_K2, IWAN_MU, JOINT_BEARING_BODY,
    JOINT_BEARING_RADIUS, JOINT_BEARING_X, JOINT_BEARING_Y, JOINT_CHI, JOINT_CLEARANCE,
    JOINT_COLUMNS, CHI_POINTS, JOINT_CHI_LOG_SPEED, JOINT_CHI_STEP, JOINT_CHI_TABLE,
    JOINT_FRICTION_LAW, JOINT_IMPACT, JOINT_JOURNAL_BODY, JOINT_JOURNAL_X,
    JOINT_JOURNAL_Y, JOINT_RESTITUTION, JOINT_REST_SPEED, JOINT_STATE, LATCH, LINEAR, LINEAR_ALPHA,
    LINEAR_MU_STATIC, LOG_COLUMNS, LOG_IMPULSE, LOG_JOINT, LOG_RATE, LOG_TIME, LUGRE,
    LUGRE_MU_COULOMB, LUGRE_MU_STATIC, LUGRE_SIGMA0, LUGRE_SIGMA1, LUGRE_SIGMA2,
    LUGRE_STRIBECK_SPEED, NO_FRICTION, POISSON, PRISMATIC_ANGLE, PRISMATIC_AXIS_ANGLE,
    PRISMATIC_AXIS_X, PRISMATIC_AXIS_Y, PRISMATIC_BODY, PRISMATIC_X, PRISMATIC_Y,
    REGULARISATION_V0, REGULARISATION_V1, REVOLUTE_BODY_I, REVOLUTE_BODY_J, REVOLUTE_X_I,
    REVOLUTE_X_J, REVOLUTE_Y_I, REVOLUTE_Y_J, STATE_STRETCH, STATE_TRAVEL, STOP, STRIBECK,
    STRIBECK_MU_MIN, STRIBECK_MU_STATIC, STRIBECK_V_MIN, TORSION_BODY_I, TORSION_BODY_J,
    TORSION_DAMPING, TORSION_FREE_ANGLE, TORSION_KIND, TORSION_STIFFNESS, WORK_IN, Contacts,
    KernelArgs,
    Impulse, Integration, JointForces, Kinematics, Record, RelativeAngle, Workspace)

LATCH_TOL = 1e-8   # rad: a latch engages within this of its angle (the step is shortened to it)


@numba.njit(cache=True)
def rot(phi, sx, sy):
    c, s = math.cos(phi), math.sin(phi)
    return c * sx - s * sy, s * sx + c * sy


@numba.njit(cache=True)
def point(q, body, sx, sy):
    """Global position of the point s of a body (body < 0: the ground, s global)."""
    if body < 0:
        return sx, sy
    ax, ay = rot(q[3 * body + 2], sx, sy)
    return q[3 * body] + ax, q[3 * body + 1] + ay


@numba.njit(cache=True)
def constraint_count(revolute, prismatic, drive):
    """Rows of the ideal joints and the drive (active contacts of impulse joints come on top)."""
    return 2 * revolute.shape[0] + 2 * prismatic.shape[0] + (1 if drive[DRIVE_BODY] >= 0 else 0)


@numba.njit(cache=True)
def fill_constraints(t, q, qd, revolute, prismatic, drive, joints, mode, alpha, jac, phi, phi_t,
                     rhs_c):
    """Phi_q into jac, Phi, Phi_t, and gamma - 2 a Phi' - a^2 Phi into rhs_c, for the ideal
    joints, the drive and the clearance joints held in persistent contact (mode 1: the
    unilateral constraint |e| - c = 0, active). Returns the number of rows used."""
    jac[:] = 0.0
    phi[:] = 0.0
    phi_t[:] = 0.0
    rhs_c[:] = 0.0  # gamma first
    row = 0
    for k in range(revolute.shape[0]):
        for body, x, y, sign in ((REVOLUTE_BODY_I, REVOLUTE_X_I, REVOLUTE_Y_I, 1.0),    # columns
                                 (REVOLUTE_BODY_J, REVOLUTE_X_J, REVOLUTE_Y_J, -1.0)):
            b = int(revolute[k, body])
            sx, sy = revolute[k, x], revolute[k, y]
            if b < 0:
                phi[row] += sign * sx
                phi[row + 1] += sign * sy
                continue
            ax, ay = rot(q[3 * b + 2], sx, sy)
            phi[row] += sign * (q[3 * b] + ax)
            phi[row + 1] += sign * (q[3 * b + 1] + ay)
            jac[row, 3 * b] += sign
            jac[row + 1, 3 * b + 1] += sign
            jac[row, 3 * b + 2] += -sign * ay
            jac[row + 1, 3 * b + 2] += sign * ax
            w2 = qd[3 * b + 2] ** 2
            rhs_c[row] += sign * ax * w2
            rhs_c[row + 1] += sign * ay * w2
        row += 2
    for k in range(prismatic.shape[0]):
        b = int(prismatic[k, PRISMATIC_BODY])
        ax, ay = rot(q[3 * b + 2], prismatic[k, PRISMATIC_X], prismatic[k, PRISMATIC_Y])
        axis = prismatic[k, PRISMATIC_AXIS_ANGLE]
        nx, ny = -math.sin(axis), math.cos(axis)
        phi[row] = (nx * (q[3 * b] + ax - prismatic[k, PRISMATIC_AXIS_X])
                    + ny * (q[3 * b + 1] + ay - prismatic[k, PRISMATIC_AXIS_Y]))
        jac[row, 3 * b] = nx
        jac[row, 3 * b + 1] = ny
        jac[row, 3 * b + 2] = -nx * ay + ny * ax
        rhs_c[row] = (nx * ax + ny * ay) * qd[3 * b + 2] ** 2
        phi[row + 1] = q[3 * b + 2] - prismatic[k, PRISMATIC_ANGLE]
        jac[row + 1, 3 * b + 2] = 1.0
        row += 2
    if drive[DRIVE_BODY] >= 0:
        b = int(drive[DRIVE_BODY])
        phi[row] = q[3 * b + 2] - drive[DRIVE_ANGLE] - drive[DRIVE_SPEED] * t
        phi_t[row] = -drive[DRIVE_SPEED]
        jac[row, 3 * b + 2] = 1.0
        row += 1
    for k in range(joints.shape[0]):
        if mode[k] == 0:
            continue
        # phi = |e| - c, e = P_j - P_b; phi'' = n.e'' + (|e'|^2 - (n.e')^2)/|e|
        kin = joint_kinematics(q, qd, joints[k])
        e = kin.delta + joints[k, JOINT_CLEARANCE]
        ex_dot = ey_dot = 0.0
        for body, x, y, sign in ((JOINT_JOURNAL_BODY, JOINT_JOURNAL_X, JOINT_JOURNAL_Y, 1.0),    # columns
                                 (JOINT_BEARING_BODY, JOINT_BEARING_X, JOINT_BEARING_Y, -1.0)):
            b = int(joints[k, body])
            if b < 0:
                continue
            ax, ay = rot(q[3 * b + 2], joints[k, x], joints[k, y])
            w = qd[3 * b + 2]
            jac[row, 3 * b] += sign * kin.nx
            jac[row, 3 * b + 1] += sign * kin.ny
            jac[row, 3 * b + 2] += sign * (-kin.nx * ay + kin.ny * ax)
            ex_dot += sign * (qd[3 * b] - w * ay)
            ey_dot += sign * (qd[3 * b + 1] + w * ax)
            rhs_c[row] += sign * w * w * (kin.nx * ax + kin.ny * ay)
        rhs_c[row] -= (ex_dot**2 + ey_dot**2 - kin.rate**2) / e
        phi[row] = kin.delta
        row += 1
    for i in range(row):
        rate = phi_t[i]
        for j in range(jac.shape[1]):
            rate += jac[i, j] * qd[j]
        rhs_c[i] -= 2 * alpha * rate + alpha * alpha * phi[i]
    return row


@numba.njit(cache=True)
def constraints(t, q, qd, revolute, prismatic, drive, alpha):
    """Phi_q, the right-hand side gamma - 2 a Phi' - a^2 Phi, Phi and Phi_t of the ideal
    joints and the drive (new arrays)."""
    m = constraint_count(revolute, prismatic, drive)
    jac, phi, phi_t, rhs_c = np.zeros((m, q.size)), np.zeros(m), np.zeros(m), np.zeros(m)
    fill_constraints(t, q, qd, revolute, prismatic, drive, np.zeros((0, JOINT_COLUMNS)),
                     np.zeros(0, np.int64), alpha, jac, phi, phi_t, rhs_c)
    return jac, rhs_c, phi, phi_t


@numba.njit(cache=True)
def cholesky_solve(a, b, m, first=None):
    """Solve a x = b in place (x in b) for the leading m x m block of a small symmetric
    positive semi-definite a (overwritten). A row that depends on the rows before it (a pivot
    below 1e-10 of its diagonal: redundant constraints, as a closed loop of revolute joints in
    space has) is dropped, its unknown set to 0: for consistent equations the others still
    solve them all. `first` (optional): the envelope of a, first[i] the column of row i's
    first nonzero in its lower triangle (a's entries left of it are not read); the factor
    keeps that envelope (fill-in stays inside it), so the sums start there: a chain of
    bodies, whose constraint rows couple only through the bodies they share, factors at a
    fraction of the dense cost."""
    for j in range(m):
        fj = envelope(first, j)
        d = a[j, j]
        scale = d
        for k in range(fj, j):
            d -= a[j, k] * a[j, k]
        if d <= 1e-10 * scale:
            a[j, j] = 0.0
            for i in range(j + 1, m):
                a[i, j] = 0.0
            continue
        a[j, j] = math.sqrt(d)
        for i in range(j + 1, m):
            fi = envelope(first, i)
            if fi > j:
                continue
            v = a[i, j]
            for k in range(max(fi, fj), j):
                v -= a[i, k] * a[j, k]
            a[i, j] = v / a[j, j]
    for i in range(m):
        v = b[i]
        for k in range(envelope(first, i), i):
            v -= a[i, k] * b[k]
        b[i] = v / a[i, i] if a[i, i] > 0.0 else 0.0
    for i in range(m - 1, -1, -1):
        v = b[i]
        for k in range(i + 1, m):
            if envelope(first, k) <= i:
                v -= a[k, i] * b[k]
        b[i] = v / a[i, i] if a[i, i] > 0.0 else 0.0


@numba.njit(cache=True, inline="always")
def envelope(first, i):
    """The first column of row i's envelope (cholesky_solve): 0 without an envelope."""
    if first is None:
        return 0
    return first[i]


@numba.njit(cache=True)
def schur_solve(jac, minv, schur, b, m, nq):
    """(Phi_q M^-1 Phi_q^T) x = b on the first m rows of jac; x into b."""
    for i in range(m):
        for k in range(i + 1):
            v = 0.0
            for c in range(nq):
                v += jac[i, c] * minv[c] * jac[k, c]
            schur[i, k] = v
            schur[k, i] = v
    cholesky_solve(schur, b, m)


@numba.njit(cache=True)
def mass_weighted_step(target, jac, minv, x, m, nq, scale):
    """target -= scale M^-1 Phi_q^T x: the least change (in the mass metric) along the rows."""
    for c in range(nq):
        v = 0.0
        for i in range(m):
            v += jac[i, c] * x[i]
        target[c] -= scale * minv[c] * v


@numba.njit(cache=True)
def joint_kinematics(q, qd, joint):
    """Penetration, normal, contact point, approach rate and slip of a clearance joint."""
    bi, bj = int(joint[JOINT_BEARING_BODY]), int(joint[JOINT_JOURNAL_BODY])
    pbx, pby = point(q, bi, joint[JOINT_BEARING_X], joint[JOINT_BEARING_Y])
    pjx, pjy = point(q, bj, joint[JOINT_JOURNAL_X], joint[JOINT_JOURNAL_Y])
    ex, ey = pjx - pbx, pjy - pby
    e = math.hypot(ex, ey)
    delta = e - joint[JOINT_CLEARANCE]
    if e == 0.0:
        return Kinematics(delta, 1.0, 0.0, pbx, pby, 0.0, 0.0)
    nx, ny = ex / e, ey / e
    cx, cy = pbx + joint[JOINT_BEARING_RADIUS] * nx, pby + joint[JOINT_BEARING_RADIUS] * ny
    vx = vy = 0.0
    for b, sign in ((bj, 1.0), (bi, -1.0)):
        if b >= 0:
            w = qd[3 * b + 2]
            vx += sign * (qd[3 * b] - w * (cy - q[3 * b + 1]))
            vy += sign * (qd[3 * b + 1] + w * (cx - q[3 * b]))
    return Kinematics(delta, nx, ny, cx, cy, vx * nx + vy * ny, -vx * ny + vy * nx)


@numba.njit(cache=True)
def joint_friction(joint, f_n, slip, state):
    """Friction force (N, along the slip: it acts against it) and the rate of the law's state,
    for every law of a clearance joint but the two-state Iwan element: the laws of
    pinbore.laws.friction with the joint's parameters, LuGre and Dahl normalised by F_n."""
    law = int(joint[JOINT_FRICTION_LAW])
    if law == NO_FRICTION:
        return 0.0, 0.0
    if law <= LINEAR:   # static laws, regularised (Ambrosio)
        if law == COULOMB:
            mu = joint[COULOMB_MU]
        elif law == STRIBECK:
            mu = friction.stribeck_polynomial(slip, joint[STRIBECK_MU_STATIC], joint[STRIBECK_MU_MIN],
                                              joint[STRIBECK_V_MIN])
        else:
            mu = friction.linear_velocity(slip, joint[LINEAR_MU_STATIC], joint[LINEAR_ALPHA])
        return friction.ambrosio(slip, f_n, mu, joint[REGULARISATION_V0], joint[REGULARISATION_V1]), 0.0
    if law == LUGRE:
        g = friction.lugre_g(slip, joint[LUGRE_MU_COULOMB], joint[LUGRE_MU_STATIC],
                             joint[LUGRE_STRIBECK_SPEED])
        rate = friction.lugre_rate(state, slip, joint[LUGRE_SIGMA0], g)
        return f_n * friction.lugre_force(state, rate, slip, joint[LUGRE_SIGMA0], joint[LUGRE_SIGMA1],
                                          joint[LUGRE_SIGMA2]), rate
    return f_n * state, friction.dahl_rate(state, slip, joint[DAHL_SIGMA], joint[DAHL_MU])


@numba.njit(cache=True)
def joint_chi(joint, impact_speed):
    """The hysteresis factor chi of a joint for the impact speed v0 of its contact: the damping
    law's constant, or (damping_law = "calibrated") the tabulated chi(v0) interpolated linearly
    in ln v0, held at the table's ends."""
    step = joint[JOINT_CHI_STEP]
    if step == 0.0:
        return joint[JOINT_CHI]
    x = (math.log(impact_speed) - joint[JOINT_CHI_LOG_SPEED]) / step
    if x <= 0.0:
        return joint[JOINT_CHI_TABLE]
    if x >= CHI_POINTS - 1:
        return joint[JOINT_CHI_TABLE + CHI_POINTS - 1]
    i = int(x)
    f = x - i
    return (1.0 - f) * joint[JOINT_CHI_TABLE + i] + f * joint[JOINT_CHI_TABLE + i + 1]


@numba.njit(cache=True)
def joint_forces(q, qd, joint, impact_speed, grid_log0, grid_step, table, y):
    """The forces of a clearance joint with a continuous contact law (layout.JointForces):
    penetration, F_n, F_t, F_el, the power into damping and friction, the normal, the contact
    point and the rates of the friction states. The power includes what the friction element
    stores in its springs (LuGre, Dahl, Iwan) and may give back."""
    kin = joint_kinematics(q, qd, joint)
    if kin.delta <= 0.0:
        return JointForces(kin.delta, 0.0, 0.0, 0.0, 0.0, kin.nx, kin.ny, kin.cx, kin.cy, 0.0, 0.0)
    f_el = tables.table_force(kin.delta, grid_log0, grid_step, table)
    f_n = dissipative.hysteresis_force(f_el, kin.rate, impact_speed, joint_chi(joint, impact_speed))
    index = int(joint[JOINT_STATE])
    if int(joint[JOINT_FRICTION_LAW]) == IWAN:
        f_t, rate0, rate1 = friction.iwan_bilinear(y[index + STATE_TRAVEL], y[index + STATE_STRETCH],
                                                   kin.slip, joint[IWAN_K1], joint[IWAN_K2],
                                                   joint[IWAN_MU] * f_n)
    else:
        f_t, rate0 = joint_friction(joint, f_n, kin.slip, y[index] if index >= 0 else 0.0)
        rate1 = 0.0
    return JointForces(kin.delta, f_n, f_t, f_el, (f_n - f_el) * kin.rate + f_t * kin.slip,
                       kin.nx, kin.ny, kin.cx, kin.cy, rate0, rate1)


@numba.njit(cache=True)
def relative_angle(q, qd, row):
    """Relative angle phi_j - phi_i beyond the element's free angle, and its rate."""
    bi, bj = int(row[TORSION_BODY_I]), int(row[TORSION_BODY_J])
    angle = ((q[3 * bj + 2] if bj >= 0 else 0.0) - (q[3 * bi + 2] if bi >= 0 else 0.0)
             - row[TORSION_FREE_ANGLE])
    rate = (qd[3 * bj + 2] if bj >= 0 else 0.0) - (qd[3 * bi + 2] if bi >= 0 else 0.0)
    return RelativeAngle(angle, rate)


@numba.njit(cache=True)
def torsion_torque(q, qd, row, latched):
    """Torque on body j (N m) of a torsion element on the planar relative angle, and the
    power its damper dissipates (torsion_law)."""
    angle, rate = relative_angle(q, qd, row)
    return torsion_law(angle, rate, row, latched)


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def workspace(args):
    """The buffers of the right-hand side (layout.Workspace), sized for every constraint row:
    the ideal joints, the drive and a held contact per clearance joint."""
    nq, nj = args.nq, args.joints.shape[0]
    m = constraint_count(args.revolute, args.prismatic, args.drive) + nj
    return Workspace(np.zeros((m, nq)), np.zeros(m), np.zeros(m), np.zeros(m), np.zeros((m, m)),
                     np.zeros(nq), np.zeros(max(nj, 1)))


@numba.njit(cache=True)
def solve_multipliers(minv, force, jac, rhs_c, schur, m, nq):
    """(Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - rhs_c on the first m rows; lambda into rhs_c."""
    for i in range(m):
        v = -rhs_c[i]
        for j in range(nq):
            v += jac[i, j] * minv[j] * force[j]
        rhs_c[i] = v
    schur_solve(jac, minv, schur, rhs_c, m, nq)


@numba.njit(cache=True)
def rhs(t, y, dy, args, work):
    """dy = f(t, y): velocities, accelerations, dissipated power, power of the constraints,
    rates of the friction states. args: layout.KernelArgs; work: layout.Workspace."""
    nq, minv, joints, torsion = args.nq, args.minv, args.joints, args.torsion
    speeds, tables, latched, mode = args.speeds, args.tables, args.latched, args.mode
    revolute, prismatic, drive = args.revolute, args.prismatic, args.drive
    jac, phi, phi_t, rhs_c, schur, force, normal = (work.jac, work.phi, work.phi_t, work.rhs_c,
                                                    work.schur, work.force, work.normal)
    q, qd = y[:nq], y[nq:2 * nq]
    for b in range(nq // 3):
        force[3 * b] = args.gravity_x / minv[3 * b]
        force[3 * b + 1] = args.gravity_y / minv[3 * b + 1]
        force[3 * b + 2] = 0.0
    dissipation = 0.0
    for i in range(2 * nq + ENERGY_STATES, y.size):
        dy[i] = 0.0   # friction states rest out of contact
    normal[:] = 0.0
    for k in range(joints.shape[0]):
        if int(joints[k, JOINT_IMPACT]) != CONTINUOUS:
            continue   # impulse joints: impacts between steps, held contact as a constraint
        c = joint_forces(q, qd, joints[k], speeds[k], args.grid_log0, args.grid_step,
                         tables[k], y)
        if c.delta <= 0.0:
            continue
        if not math.isfinite(c.f_n):
            dy[:] = math.nan   # penetration beyond the tabulated law: the integrator stops
            return
        index = int(joints[k, JOINT_STATE])
        if index >= 0:
            dy[index] = c.state_rate
            if int(joints[k, JOINT_FRICTION_LAW]) == IWAN:
                dy[index + STATE_STRETCH] = c.second_state_rate
        normal[k] = c.f_n
        fx, fy = -c.f_n * c.nx + c.f_t * c.ny, -c.f_n * c.ny - c.f_t * c.nx   # on the journal
        for b, sign in ((int(joints[k, JOINT_JOURNAL_BODY]), 1.0),
                        (int(joints[k, JOINT_BEARING_BODY]), -1.0)):
            if b >= 0:
                force[3 * b] += sign * fx
                force[3 * b + 1] += sign * fy
                force[3 * b + 2] += sign * ((c.cx - q[3 * b]) * fy - (c.cy - q[3 * b + 1]) * fx)
        dissipation += c.power
    for k in range(torsion.shape[0]):
        torque, power = torsion_torque(q, qd, torsion[k], latched[k] > 0)
        bi, bj = int(torsion[k, TORSION_BODY_I]), int(torsion[k, TORSION_BODY_J])
        if bj >= 0:
            force[3 * bj + 2] += torque
        if bi >= 0:
            force[3 * bi + 2] -= torque
        dissipation += power
    dy[:nq] = qd
    m = fill_constraints(t, q, qd, revolute, prismatic, drive, joints, mode,
                         args.baumgarte, jac, phi, phi_t, rhs_c)
    work_in = 0.0
    if m > 0:
        solve_multipliers(minv, force, jac, rhs_c, schur, m, nq)
        for j in range(nq):
            v = force[j]
            for i in range(m):
                v -= jac[i, j] * rhs_c[i]
            dy[nq + j] = minv[j] * v
        for i in range(m):
            work_in += rhs_c[i] * phi_t[i]
        row = constraint_count(revolute, prismatic, drive)
        for k in range(joints.shape[0]):
            if mode[k] == 1:
                normal[k] = rhs_c[row]   # the multiplier of |e| - c = 0 is the normal force
                row += 1
    else:
        for j in range(nq):
            dy[nq + j] = minv[j] * force[j]
    dy[2 * nq + DISSIPATED] = dissipation
    dy[2 * nq + WORK_IN] = work_in


def rhs_value(t, y, args):
    """(f(t, y), normal force per clearance joint) as new arrays (Python-side convenience)."""
    dy, work = integrator.evaluate_once(workspace, rhs, t, y, args)
    return dy, work.normal[:args.joints.shape[0]].copy()


@numba.njit(cache=True)
def apply_impulse(t, y, args, work, j, target_restitution):
    """Impact of impulse joint j (approaching at delta' = v > 0): the velocity jump of least
    kinetic-energy change that keeps every ideal joint and held contact and leaves the
    joint's approach rate at -e v, i.e. qd+ = qd - M^-1 G^T (G M^-1 G^T)^-1 (G qd - b) with G
    the constraint rows plus the joint's normal. Newton's hypothesis sets e on velocities
    directly; Poisson's applies the compression impulse P_c (rate to 0) and then e P_c. For a
    frictionless impact the two coincide (the normal rate is linear in the impulse).
    Returns the layout.Impulse: normal impulse on the journal (N s), energy dissipated (J),
    work of the drive's impulse (J)."""
    nq, minv, joints, mode = args.nq, args.minv, args.joints, args.mode
    jac, phi_t, rhs_c = work.jac, work.phi_t, work.rhs_c
    q, qd = y[:nq], y[nq:2 * nq]
    rate = joint_kinematics(q, qd, joints[j]).rate
    before = 0.0
    for i in range(nq):
        before += 0.5 * qd[i] ** 2 / minv[i]
    held = mode[j]
    mode[j] = 1
    m = fill_constraints(t, q, qd, args.revolute, args.prismatic, args.drive, joints, mode, 0.0, jac,
                         work.phi, phi_t, rhs_c)
    mode[j] = held
    row = constraint_count(args.revolute, args.prismatic, args.drive)
    for k in range(j):
        row += mode[k]
    poisson = int(joints[j, JOINT_IMPACT]) == POISSON
    e = target_restitution
    rhs_c[:m] = 0.0
    rhs_c[row] = rate if poisson else (1.0 + e) * rate
    schur_solve(jac, minv, work.schur, rhs_c, m, nq)
    scale = (1.0 + e) if poisson else 1.0
    mass_weighted_step(qd, jac, minv, rhs_c, m, nq, scale)
    after = 0.0
    for c in range(nq):
        after += 0.5 * qd[c] ** 2 / minv[c]
    work_in = 0.0   # the drive's impulse works on its prescribed speed
    for i in range(m):
        work_in += scale * rhs_c[i] * phi_t[i]
    return Impulse(scale * rhs_c[row], before - after + work_in, work_in)


@numba.njit(cache=True)
def project_onto_constraints(t, y, args, work, tolerance, rate_tolerance):
    """One Gauss-Newton step of positions and then velocities onto Phi = 0 and
    Phi_q q' + Phi_t = 0 (ideal joints, drive, held contacts), least change in the mass
    metric: dq = -M^-1 Phi_q^T (Phi_q M^-1 Phi_q^T)^-1 Phi, each only where the residual
    exceeds its tolerance (m, m/s). Keeps the drift of accepted steps from accumulating where
    Baumgarte alone is too slow (loose tolerances, fast drives). Returns whether y changed."""
    nq, minv = args.nq, args.minv
    revolute, prismatic, drive = args.revolute, args.prismatic, args.drive
    joints, mode = args.joints, args.mode
    jac, phi, phi_t, rhs_c, schur = work.jac, work.phi, work.phi_t, work.rhs_c, work.schur
    changed = False
    for level in range(2):
        q, qd = y[:nq], y[nq:2 * nq]
        m = fill_constraints(t, q, qd, revolute, prismatic, drive, joints, mode, 0.0, jac, phi,
                             phi_t, rhs_c)
        largest = 0.0
        for i in range(m):
            if level == 0:
                rhs_c[i] = phi[i]
            else:
                v = phi_t[i]
                for c in range(nq):
                    v += jac[i, c] * qd[c]
                rhs_c[i] = v
            largest = max(largest, abs(rhs_c[i]))
        if largest <= (tolerance if level == 0 else rate_tolerance):
            continue
        changed = True
        schur_solve(jac, minv, schur, rhs_c, m, nq)
        mass_weighted_step(y[:nq] if level == 0 else y[nq:2 * nq], jac, minv, rhs_c, m, nq, 1.0)
    return changed


@numba.njit(cache=True)
def impulse_energy(y, nq, impulse):
    """Book an impulse's dissipation and drive work in the energy states; the impulse."""
    y[2 * nq + DISSIPATED] += impulse.dissipated
    y[2 * nq + WORK_IN] += impulse.work_in
    return impulse.impulse


# ---- the phases of integrate (reduced.integrator) that are the planar mechanism's own
# Passing the bundles to every helper (a dozen calls a step) made the slider-crank's run a
# fifth slower than the monolithic loop; the helpers that run every step take the arrays they
# use, and those for held contacts, Iwan elements and latches run only for mechanisms that
# have them.


@numba.njit(cache=True)
def onset_fraction(y_new, nq, joints, mode, contacts, onset_tol):
    """Event location: the fraction of a trial step that ends it at the first contact onset
    of a free joint (integrator.onset_shortening). 1: no onset."""
    depth, in_contact = contacts.depth, contacts.in_contact
    shorten = 1.0
    for j in range(joints.shape[0]):
        if not in_contact[j] and mode[j] == 0:
            d_new = joint_kinematics(y_new[:nq], y_new[nq:2 * nq], joints[j]).delta
            shorten = min(shorten, integrator.onset_shortening(depth[j], d_new, onset_tol))
    return shorten


@numba.njit(cache=True)
def release_fraction(mode, normal, contacts, rtol):
    """Event location: the fraction of a trial step that ends it where a held contact's force
    (normal: at the step's end, the last rhs evaluation's multipliers) turns pulling, by a
    secant on the force. 1: no release."""
    held_force, held_peak = contacts.held_force, contacts.held_peak
    shorten = 1.0
    for j in range(mode.size):
        if mode[j] == 1:
            f_new = normal[j]
            if held_force[j] > 0.0 and f_new < -1e-3 * math.sqrt(rtol) * held_peak[j]:
                shorten = min(shorten, 0.99 * held_force[j] / (held_force[j] - f_new))
    return shorten


@numba.njit(cache=True)
def latch_fraction(y, y_new, nq, torsion, latched):
    """Event location: the fraction of a trial step that ends it where a latch reaches its
    angle (secant on the angle). 1: no latch."""
    shorten = 1.0
    for r in range(torsion.shape[0]):
        if latched[r] == 0.0 and int(torsion[r, TORSION_KIND]) == LATCH:
            a_new = relative_angle(y_new[:nq], y_new[nq:2 * nq], torsion[r]).angle
            if a_new > LATCH_TOL:
                a_old = relative_angle(y[:nq], y[nq:2 * nq], torsion[r]).angle
                shorten = min(shorten, 0.99 * (-a_old) / (a_new - a_old))
    return shorten


@numba.njit(cache=True)
def release_held_contacts(t, y, args, work, contacts):
    """Accepted step: the held contacts' forces (the multipliers at the step's end); one that
    pulls releases, and an approach rate left by drift is removed (an impulse with e = 0).
    Returns whether a contact was released."""
    nq, joints, mode, normal = args.nq, args.joints, args.mode, work.normal
    held_force, held_peak = contacts.held_force, contacts.held_peak
    changed = False
    for j in range(joints.shape[0]):
        if mode[j] == 1:
            held_force[j] = normal[j]
            held_peak[j] = max(held_peak[j], held_force[j])
            if held_force[j] < 0.0:   # released; an approach rate left by drift is removed
                if joint_kinematics(y[:nq], y[nq:2 * nq], joints[j]).rate > 0.0:
                    impulse_energy(y, nq, apply_impulse(t, y, args, work, j, 0.0))
                mode[j] = 0
                changed = True
    return changed



@numba.njit(cache=True)
def onsets_and_impacts(t, y, args, work, contacts, onset_tol, speed_floor, log, impacts):
    """Accepted step, per clearance joint: the penetration; an impulse joint arriving
    (approaching within onset_tol) takes its impact, and one too slow to rebound is held in
    contact; a continuous joint arriving records its impact speed v0 (at least speed_floor)
    and restarts its Iwan element unloaded; one that left contact is marked free. Every
    impact and onset goes into the log. Returns (whether anything happened, impacts, log)."""
    nq, joints, mode, speeds = args.nq, args.joints, args.mode, args.speeds
    depth, in_contact = contacts.depth, contacts.in_contact
    changed = False
    for j in range(joints.shape[0]):
        kin = joint_kinematics(y[:nq], y[nq:2 * nq], joints[j])
        delta, rate = kin.delta, kin.rate
        depth[j] = delta
        onset, impulse = False, 0.0
        if int(joints[j, JOINT_IMPACT]) != CONTINUOUS:
            if mode[j] == 0 and delta > -onset_tol and rate > 0.0:
                restitution = joints[j, JOINT_RESTITUTION]
                e = restitution if restitution * rate >= joints[j, JOINT_REST_SPEED] else 0.0
                impulse = impulse_energy(y, nq, apply_impulse(t, y, args, work, j, e))
                if e == 0.0:   # too slow to rebound: held contact (the third state)
                    mode[j] = 1
                    contacts.held_force[j] = contacts.held_peak[j] = 0.0
                speeds[j] = rate
                onset = True
        elif not in_contact[j] and delta > -onset_tol:
            in_contact[j] = True
            speeds[j] = max(rate, speed_floor)
            if int(joints[j, JOINT_FRICTION_LAW]) == IWAN:   # a new contact point: unloaded
                index = int(joints[j, JOINT_STATE])
                y[index + STATE_TRAVEL] = y[index + STATE_STRETCH] = 0.0
            onset = True
        elif in_contact[j] and delta < -onset_tol:
            in_contact[j] = False
        if onset:
            changed = True
            impacts += 1
            log = log_impact(log, impacts, t, j, rate, impulse)
    return changed, impacts, log


@numba.njit(cache=True)
def iwan_slider_return(y, args, contacts):
    """Accepted step: the Iwan slider of every joint in contact held to |k1 z| <= mu F_n
    (laws.friction.iwan_return_map at the accepted state). Returns whether a slider moved."""
    nq, joints, speeds, tables = args.nq, args.joints, args.speeds, args.tables
    in_contact = contacts.in_contact
    changed = False
    for j in range(joints.shape[0]):
        if int(joints[j, JOINT_FRICTION_LAW]) == IWAN and in_contact[j]:
            f_n = joint_forces(y[:nq], y[nq:2 * nq], joints[j], speeds[j], args.grid_log0,
                               args.grid_step, tables[j], y).f_n
            stretch = int(joints[j, JOINT_STATE]) + STATE_STRETCH
            held = friction.iwan_return_map(y[stretch], joints[j, IWAN_K1], joints[j, IWAN_MU] * f_n)
            if held != y[stretch]:
                y[stretch] = held
                changed = True
    return changed


@numba.njit(cache=True)
def engage_latches(y, nq, torsion, latched):
    """Latch every latch that has reached its angle (to within LATCH_TOL). Returns whether
    one engaged."""
    changed = False
    for r in range(torsion.shape[0]):
        if latched[r] == 0.0 and int(torsion[r, TORSION_KIND]) == LATCH and \
                relative_angle(y[:nq], y[nq:2 * nq], torsion[r]).angle > -LATCH_TOL:
            latched[r] = 1.0
            changed = True
    return changed



# ---- the planar mechanism's hooks of the integrator (reduced.integrator), chosen by KernelArgs
def planar(args) -> bool:
    return getattr(args, "instance_class", None) is KernelArgs


@overload(integrator.new_workspace, inline="always")
def _new_workspace(args):
    if planar(args):
        return lambda args: workspace(args)


@overload(integrator.evaluate, inline="always")
def _evaluate(t, y, dy, args, work):
    if planar(args):
        return rhs.py_func


@numba.njit(cache=True)
def start(y, args, onset_tol):
    """The contact state at t = 0 (latches given as engaged engage) and what this mechanism
    needs checked: (impulse joints, Iwan elements, latches)."""
    nq, joints, torsion = args.nq, args.joints, args.torsion
    nj = joints.shape[0]
    impulse_joints = iwan_joints = latches = False
    for j in range(nj):
        impulse_joints |= int(joints[j, JOINT_IMPACT]) != CONTINUOUS
        iwan_joints |= int(joints[j, JOINT_FRICTION_LAW]) == IWAN
    for r in range(torsion.shape[0]):
        latches |= int(torsion[r, TORSION_KIND]) == LATCH
    engage_latches(y, nq, torsion, args.latched)   # a latch given as engaged stays so
    contacts = Contacts(np.zeros(nj), np.zeros(nj, np.bool_), np.zeros(nj), np.zeros(nj))
    for j in range(nj):
        contacts.depth[j] = joint_kinematics(y[:nq], y[nq:2 * nq], joints[j]).delta
        contacts.in_contact[j] = (contacts.depth[j] > -onset_tol
                                  and int(joints[j, JOINT_IMPACT]) == CONTINUOUS)
    return contacts, (impulse_joints, iwan_joints, latches)


@overload(integrator.start, inline="always")
def _start(y, args, onset_tol):
    if planar(args):
        return lambda y, args, onset_tol: start(y, args, onset_tol)


@overload(integrator.event_fraction, inline="always")
def _event_fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt):
    if planar(args):
        def fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt):
            nq = args.nq
            shorten = onset_fraction(y_new, nq, args.joints, args.mode, contacts, onset_tol)
            if needs[0] and h > event_dt:
                shorten = min(shorten, release_fraction(args.mode, work.normal, contacts, rtol))
            if needs[2]:
                shorten = min(shorten, latch_fraction(y, y_new, nq, args.torsion, args.latched))
            return shorten
        return fraction


@overload(integrator.after_step, inline="always")
def _after_step(t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, log, impacts):
    if planar(args):
        def updates(t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, log,
                    impacts):
            changed = needs[0] and release_held_contacts(t, y, args, work, contacts)
            arrived, impacts, log = onsets_and_impacts(t, y, args, work, contacts, onset_tol,
                                                       speed_floor, log, impacts)
            slid = needs[1] and iwan_slider_return(y, args, contacts)
            engaged = needs[2] and engage_latches(y, args.nq, args.torsion, args.latched)
            projected = project_onto_constraints(t, y, args, work, onset_tol, rate_tol)
            return projected or changed or arrived or slid or engaged, impacts, log
        return updates



# ---- the compiled code follows the laws and the layout
# numba's cache checks only the file a compiled function is defined in: the kernel compiles in
# the laws of pinbore.laws.friction, .dissipative and .tables and the constants of
# reduced.layout, so an edit there alone would leave the kernel's cached code stale
# (pinbore.core.compiled: a digest of those files drops the kernel's cache when they change).
COMPILED_IN = (friction.__file__, dissipative.__file__, tables.__file__, layout.__file__,
               integrator.__file__)
follow_compiled_in(globals(), COMPILED_IN)
