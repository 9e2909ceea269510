r"""The compiled core of the reduced model: equations of motion and the integrator.

Planar rigid bodies with coordinates q = (x_k, y_k, phi_k) of their centres of mass,
M = diag(m_k, m_k, J_k). Ideal joints and the drive are constraints Phi(q, t) = 0 with
Lagrange multipliers (review eq. 21):

    M q'' + Phi_q^T lambda = Q(q, q', t),
    Phi_q q''  = gamma - 2 a Phi' - a^2 Phi          (Baumgarte, a the stabilisation rate).

M is diagonal, so lambda comes from the small Schur system (Phi_q M^-1 Phi_q^T) lambda =
Phi_q M^-1 Q - gamma~. Revolute joints Phi = r_i + A_i s_i - r_j - A_j s_j, prismatic joints
n.(r + A s - P) = 0 and phi = phi_0, the drive phi = phi_0 + omega t.

A revolute clearance joint is no constraint: the journal centre P_j moves inside the bearing
(centre P_b, radius R_b, clearance c = R_b - R_j). With e = P_j - P_b, the penetration is
delta = |e| - c, the normal n = e/|e|, the contact point P_b + R_b n. While delta > 0 the
normal force is F_n = F_el(delta) (1 + chi delta'/v0)  (>= 0), F_el from a table of the
elastic law (log-log interpolation, exact for a power law), chi the hysteresis factor of the
damping law, v0 the approach rate at the onset of this impact; the friction force
opposes the tangential slip v_t: Ambrosio's regularised Coulomb, polynomial Stribeck or a
linear velocity law (static, regularised near zero slip), or LuGre or Dahl normalised by F_n,
whose states are integrated with the motion (and rest while the joint is open). While
delta <= 0 no law is evaluated.

Extra states integrate the energy dissipated in the joints and the work of the constraint
forces (the drive), so the energy balance can be checked.

Integrator: Dormand-Prince 5(4) with a PI step-size controller on (q, q') and the friction
states. A trial step with
a stage beyond the tabulated law (NaN) is retried ten times shorter; only if the step size
collapses that way has the run blown up. A step that would carry a joint from free flight
into contact deeper than `onset_tol` is shortened (secant on delta) until it ends at the
onset; there v0 is recorded. So every impact starts on a step boundary with a known impact
speed. Latches engage the same way, at their angle, so their spring starts unloaded. The right-hand side works in preallocated buffers and solves the Schur system by
Cholesky: about 1 us per evaluation for the slider-crank.
"""

import math

import numba
import numpy as np

# status codes
OK, BLOWN_UP, TOO_MANY_STEPS, STEP_TOO_SMALL = 0, 1, 2, 3
# friction laws of a clearance joint (column 9 of its row)
NO_FRICTION, COULOMB, STRIBECK, LINEAR, LUGRE, DAHL = 0, 1, 2, 3, 4, 5


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
    return 2 * revolute.shape[0] + 2 * prismatic.shape[0] + (1 if drive[0] >= 0 else 0)


@numba.njit(cache=True)
def fill_constraints(t, q, qd, revolute, prismatic, drive, alpha, jac, phi, phi_t, rhs_c):
    """Phi_q into jac (m x n), Phi, Phi_t, and gamma - 2 a Phi' - a^2 Phi into rhs_c."""
    jac[:] = 0.0
    phi[:] = 0.0
    phi_t[:] = 0.0
    rhs_c[:] = 0.0  # gamma first
    row = 0
    for k in range(revolute.shape[0]):
        for side, sign in ((0, 1.0), (3, -1.0)):
            b = int(revolute[k, side])
            sx, sy = revolute[k, side + 1], revolute[k, side + 2]
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
        b = int(prismatic[k, 0])
        ax, ay = rot(q[3 * b + 2], prismatic[k, 1], prismatic[k, 2])
        nx, ny = -math.sin(prismatic[k, 5]), math.cos(prismatic[k, 5])
        phi[row] = nx * (q[3 * b] + ax - prismatic[k, 3]) + ny * (q[3 * b + 1] + ay - prismatic[k, 4])
        jac[row, 3 * b] = nx
        jac[row, 3 * b + 1] = ny
        jac[row, 3 * b + 2] = -nx * ay + ny * ax
        rhs_c[row] = (nx * ax + ny * ay) * qd[3 * b + 2] ** 2
        phi[row + 1] = q[3 * b + 2] - prismatic[k, 6]
        jac[row + 1, 3 * b + 2] = 1.0
        row += 2
    if drive[0] >= 0:
        b = int(drive[0])
        phi[row] = q[3 * b + 2] - drive[2] - drive[1] * t
        phi_t[row] = -drive[1]
        jac[row, 3 * b + 2] = 1.0
    m, n = jac.shape
    for i in range(m):
        rate = phi_t[i]
        for j in range(n):
            rate += jac[i, j] * qd[j]
        rhs_c[i] -= 2 * alpha * rate + alpha * alpha * phi[i]


@numba.njit(cache=True)
def constraints(t, q, qd, revolute, prismatic, drive, alpha):
    """Phi_q, the right-hand side gamma - 2 a Phi' - a^2 Phi, Phi and Phi_t (new arrays)."""
    m = constraint_count(revolute, prismatic, drive)
    jac, phi, phi_t, rhs_c = np.zeros((m, q.size)), np.zeros(m), np.zeros(m), np.zeros(m)
    fill_constraints(t, q, qd, revolute, prismatic, drive, alpha, jac, phi, phi_t, rhs_c)
    return jac, rhs_c, phi, phi_t


@numba.njit(cache=True)
def cholesky_solve(a, b):
    """Solve a x = b in place (x in b) for a small symmetric positive definite a (overwritten)."""
    m = b.size
    for j in range(m):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        a[j, j] = math.sqrt(d)
        for i in range(j + 1, m):
            v = a[i, j]
            for k in range(j):
                v -= a[i, k] * a[j, k]
            a[i, j] = v / a[j, j]
    for i in range(m):
        v = b[i]
        for k in range(i):
            v -= a[i, k] * b[k]
        b[i] = v / a[i, i]
    for i in range(m - 1, -1, -1):
        v = b[i]
        for k in range(i + 1, m):
            v -= a[k, i] * b[k]
        b[i] = v / a[i, i]


@numba.njit(cache=True)
def elastic_force(delta, grid_log0, grid_step, table):
    """F_el(delta) from log F tabulated on a uniform grid of log delta: power law below the
    grid, NaN above it (beyond the joint's scale, or the law's range), which stops the run."""
    x = (math.log(delta) - grid_log0) / grid_step
    if x > table.size - 1 or not math.isfinite(table[min(max(int(x) + 1, 0), table.size - 1)]):
        return math.nan
    i = min(max(int(math.floor(x)), 0), table.size - 2)
    return math.exp(table[i] + (x - i) * (table[i + 1] - table[i]))


@numba.njit(cache=True)
def joint_kinematics(q, qd, joint):
    """Penetration, normal, contact point, approach rate and slip of a clearance joint."""
    bi, bj = int(joint[0]), int(joint[3])
    pbx, pby = point(q, bi, joint[1], joint[2])
    pjx, pjy = point(q, bj, joint[4], joint[5])
    ex, ey = pjx - pbx, pjy - pby
    e = math.hypot(ex, ey)
    delta = e - joint[6]
    if e == 0.0:
        return delta, 1.0, 0.0, pbx, pby, 0.0, 0.0
    nx, ny = ex / e, ey / e
    cx, cy = pbx + joint[7] * nx, pby + joint[7] * ny
    vx = vy = 0.0
    for b, sign in ((bj, 1.0), (bi, -1.0)):
        if b >= 0:
            w = qd[3 * b + 2]
            vx += sign * (qd[3 * b] - w * (cy - q[3 * b + 1]))
            vy += sign * (qd[3 * b + 1] + w * (cx - q[3 * b]))
    return delta, nx, ny, cx, cy, vx * nx + vy * ny, -vx * ny + vy * nx


@numba.njit(cache=True)
def friction(joint, f_n, slip, state):
    """Friction force (N, positive along the slip: it acts against it) and the rate of the
    law's state. joint[9] is the law, joint[10:17] its parameters; see reduced.scene."""
    law, p = int(joint[9]), joint[10:17]
    speed = abs(slip)
    sign = 1.0 if slip > 0 else -1.0
    if law == NO_FRICTION:
        return 0.0, 0.0
    if law <= LINEAR:   # static laws, regularised (Ambrosio) between p[5] and p[6]
        cd = 0.0 if speed <= p[5] else (speed - p[5]) / (p[6] - p[5]) if speed <= p[6] else 1.0
        if law == COULOMB:
            mu = p[0]
        elif law == STRIBECK:   # mu_s - k1 v + k3 v^3, minimum mu_m at v_m
            k = p[0] - p[1]
            mu = p[0] - 1.5 * k / p[2] * speed + 0.5 * k / p[2] ** 3 * speed**3
        else:
            mu = p[0] + p[1] * speed
        return mu * cd * f_n * sign, 0.0
    if law == LUGRE:
        g = p[0] + (p[1] - p[0]) * math.exp(-(slip / p[2]) ** 2)
        rate = slip - p[3] * speed * state / g
        return f_n * (p[3] * state + p[4] * rate + p[5] * slip), rate
    rate = p[1] * (1.0 - state / p[0] * sign) * slip   # Dahl, normalised
    return f_n * state, rate


@numba.njit(cache=True)
def damped_normal_force(f_el, rate, chi, impact_speed):
    """F_n = F_el (1 + chi delta' / v0), never pulling."""
    return max(f_el * (1.0 + chi * rate / impact_speed), 0.0)


@numba.njit(cache=True)
def joint_forces(q, qd, joint, impact_speed, grid_log0, grid_step, table, state):
    """(delta, F_n, F_t, F_el, dissipated power, n_x, n_y, c_x, c_y, state rate) of a
    clearance joint. Row: bearing body and point, journal body and point, clearance, bearing
    radius, hysteresis factor chi, friction law and parameters, friction state index."""
    delta, nx, ny, cx, cy, rate, slip = joint_kinematics(q, qd, joint)
    if delta <= 0.0:
        return delta, 0.0, 0.0, 0.0, 0.0, nx, ny, cx, cy, 0.0
    f_el = elastic_force(delta, grid_log0, grid_step, table)
    f_n = damped_normal_force(f_el, rate, joint[8], impact_speed)
    f_t, state_rate = friction(joint, f_n, slip, state)
    return delta, f_n, f_t, f_el, (f_n - f_el) * rate + f_t * slip, nx, ny, cx, cy, state_rate


@numba.njit(cache=True)
def relative_angle(q, qd, row):
    """Relative angle phi_j - phi_i beyond the element's free angle, and its rate."""
    bi, bj = int(row[0]), int(row[1])
    angle = (q[3 * bj + 2] if bj >= 0 else 0.0) - (q[3 * bi + 2] if bi >= 0 else 0.0) - row[4]
    rate = (qd[3 * bj + 2] if bj >= 0 else 0.0) - (qd[3 * bi + 2] if bi >= 0 else 0.0)
    return angle, rate


SPRING, STOP, LATCH = 0, 1, 2
LATCH_TOL = 1e-8   # rad: a latch engages within this of its angle (the step is shortened to it)


@numba.njit(cache=True)
def torsion_torque(q, qd, row, latched):
    """Torque on body j (N m) of a torsion spring, stop or latch, and the power its damper
    dissipates. Row: body i, body j, stiffness, damping, free angle (rad), kind. A stop acts
    beyond its angle and only pushes; a latch, once reached (`latched`), holds both ways."""
    angle, rate = relative_angle(q, qd, row)
    kind = int(row[5])
    if kind == LATCH:
        if latched:
            return -row[2] * angle - row[3] * rate, row[3] * rate * rate
        return 0.0, 0.0
    if kind == STOP and angle <= 0.0:
        return 0.0, 0.0
    torque = -row[2] * angle - row[3] * rate
    if kind == STOP and torque > 0.0:   # a stop pushes, never pulls: its stored energy is lost
        return 0.0, -row[2] * angle * rate
    return torque, row[3] * rate * rate


@numba.njit(cache=True)
def workspace(nq, revolute, prismatic, drive):
    """Buffers of the right-hand side: Phi_q, Phi, Phi_t, rhs_c, the Schur matrix, forces."""
    m = constraint_count(revolute, prismatic, drive)
    return (np.zeros((m, nq)), np.zeros(m), np.zeros(m), np.zeros(m), np.zeros((m, m)),
            np.zeros(nq))


@numba.njit(cache=True)
def rhs(t, y, dy, nq, minv, gravity, revolute, prismatic, drive, alpha, joints, speeds,
        grid_log0, grid_step, tables, torsion, latched, work):
    """dy = f(t, y): velocities, accelerations, dissipated power, power of the constraints."""
    jac, phi, phi_t, rhs_c, schur, force = work
    q, qd = y[:nq], y[nq:2 * nq]
    for b in range(nq // 3):
        force[3 * b] = gravity[0] / minv[3 * b]
        force[3 * b + 1] = gravity[1] / minv[3 * b + 1]
        force[3 * b + 2] = 0.0
    dissipation = 0.0
    for i in range(2 * nq + 2, y.size):
        dy[i] = 0.0   # friction states rest out of contact
    for k in range(joints.shape[0]):
        index = int(joints[k, 17])
        delta, f_n, f_t, f_el, power, nx, ny, cx, cy, state_rate = joint_forces(
            q, qd, joints[k], speeds[k], grid_log0, grid_step, tables[k],
            y[index] if index >= 0 else 0.0)
        if delta <= 0.0:
            continue
        if index >= 0:
            dy[index] = state_rate
        if not math.isfinite(f_n):
            dy[:] = math.nan   # penetration beyond the tabulated law: the integrator stops
            return
        fx, fy = -f_n * nx + f_t * ny, -f_n * ny - f_t * nx   # on the journal
        for b, sign in ((int(joints[k, 3]), 1.0), (int(joints[k, 0]), -1.0)):
            if b >= 0:
                force[3 * b] += sign * fx
                force[3 * b + 1] += sign * fy
                force[3 * b + 2] += sign * ((cx - q[3 * b]) * fy - (cy - q[3 * b + 1]) * fx)
        dissipation += power
    for k in range(torsion.shape[0]):
        torque, power = torsion_torque(q, qd, torsion[k], latched[k] > 0)
        bi, bj = int(torsion[k, 0]), int(torsion[k, 1])
        if bj >= 0:
            force[3 * bj + 2] += torque
        if bi >= 0:
            force[3 * bi + 2] -= torque
        dissipation += power
    dy[:nq] = qd
    m = rhs_c.size
    work_in = 0.0
    if m > 0:
        fill_constraints(t, q, qd, revolute, prismatic, drive, alpha, jac, phi, phi_t, rhs_c)
        # (Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - rhs_c, lambda into rhs_c
        for i in range(m):
            v = -rhs_c[i]
            for j in range(nq):
                v += jac[i, j] * minv[j] * force[j]
            rhs_c[i] = v
            for k in range(i + 1):
                v = 0.0
                for j in range(nq):
                    v += jac[i, j] * minv[j] * jac[k, j]
                schur[i, k] = v
                schur[k, i] = v
        cholesky_solve(schur, rhs_c)
        for j in range(nq):
            v = force[j]
            for i in range(m):
                v -= jac[i, j] * rhs_c[i]
            dy[nq + j] = minv[j] * v
        for i in range(m):
            work_in += rhs_c[i] * phi_t[i]
    else:
        for j in range(nq):
            dy[nq + j] = minv[j] * force[j]
    dy[2 * nq] = dissipation
    dy[2 * nq + 1] = work_in


def rhs_value(t, y, model_args):
    """f(t, y) as a new array (Python-side convenience)."""
    dy = np.empty_like(y)
    rhs(t, y, dy, *model_args, workspace(model_args[0], model_args[3], model_args[4], model_args[5]))
    return dy


# Dormand-Prince 5(4) tableau
C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
A = np.array([[0, 0, 0, 0, 0, 0], [1 / 5, 0, 0, 0, 0, 0], [3 / 40, 9 / 40, 0, 0, 0, 0],
              [44 / 45, -56 / 15, 32 / 9, 0, 0, 0],
              [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0],
              [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0],
              [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]])
B5 = np.array([35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0])
E54 = B5 - np.array([5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])


@numba.njit(cache=True)
def integrate(y0, t_end, nq, minv, gravity, revolute, prismatic, drive, alpha, joints,
              grid_log0, grid_step, tables, torsion, rtol, atol, max_step, onset_tol, speed_floor,
              max_steps):
    """Adaptive DOPRI5 from t = 0. Returns times, states and impact speeds of every accepted
    step, counters (accepted, rejected, rhs calls, impacts) and a status code."""
    ny = y0.size
    nj = joints.shape[0]
    capacity = 4096
    times = np.empty(capacity)
    states = np.empty((capacity, ny))
    speeds_out = np.empty((capacity, max(nj, 1)))
    speeds = np.full(nj, speed_floor)
    latched = np.zeros(torsion.shape[0])
    for r in range(torsion.shape[0]):
        latched[r] = 1.0 if int(torsion[r, 5]) == LATCH and relative_angle(
            y0[:nq], y0[nq:2 * nq], torsion[r])[0] > -LATCH_TOL else 0.0
    t, y = 0.0, y0.copy()
    k = np.empty((7, ny))
    ys = np.empty(ny)
    work = workspace(nq, revolute, prismatic, drive)
    rhs(t, y, k[0], nq, minv, gravity, revolute, prismatic, drive, alpha, joints, speeds,
        grid_log0, grid_step, tables, torsion, latched, work)
    calls, accepted, rejected, impacts = 1, 0, 0, 0
    h = min(max_step, 1e-6)
    err_prev = 1e-4
    times[0], states[0], speeds_out[0, :nj] = t, y, speeds
    count = 1
    status = OK
    last_nan = False
    depth = np.zeros(nj)                  # penetration at the last accepted state
    in_contact = np.zeros(nj, np.bool_)   # between an onset and the next separation
    for j in range(nj):
        depth[j] = joint_kinematics(y[:nq], y[nq:2 * nq], joints[j])[0]
        in_contact[j] = depth[j] > -onset_tol
    while t < t_end:
        if accepted + rejected >= max_steps:
            status = TOO_MANY_STEPS
            break
        h = min(h, t_end - t, max_step)
        if h < 1e-15 * max(t, 1e-3):
            status = BLOWN_UP if last_nan else STEP_TOO_SMALL
            break
        for s in range(1, 7):
            for i in range(ny):
                v = y[i]
                for r in range(s):
                    v += h * A[s, r] * k[r, i]
                ys[i] = v
            rhs(t + C[s] * h, ys, k[s], nq, minv, gravity, revolute, prismatic, drive, alpha,
                joints, speeds, grid_log0, grid_step, tables, torsion, latched, work)
        calls += 6
        y_new = ys.copy()  # stage 7 is evaluated at the 5th-order solution (FSAL)
        err = 0.0
        for i in range(ny):
            if i == 2 * nq or i == 2 * nq + 1:
                continue  # the energy integrals are outputs, not controlled
            e = 0.0
            for r in range(7):
                e += E54[r] * k[r, i]
            scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
            err += (h * e / scale) ** 2
        err = math.sqrt(err / (ny - 2))
        last_nan = not math.isfinite(err)
        if last_nan:   # a stage went beyond the tabulated law: much smaller step
            rejected += 1
            h *= 0.1
            continue
        if err > 1.0:
            rejected += 1
            h *= max(0.2, 0.9 * err ** -0.2)
            continue
        # a free joint would end the step in contact: shorten the step to end at the onset
        shorten = 1.0
        for j in range(nj):
            if not in_contact[j]:
                d_new = joint_kinematics(y_new[:nq], y_new[nq:2 * nq], joints[j])[0]
                if d_new > onset_tol:
                    shorten = min(shorten, 0.99 * (-depth[j]) / (d_new - depth[j]))
        for r in range(torsion.shape[0]):
            if latched[r] == 0.0 and int(torsion[r, 5]) == LATCH:
                a_new = relative_angle(y_new[:nq], y_new[nq:2 * nq], torsion[r])[0]
                if a_new > LATCH_TOL:
                    a_old = relative_angle(y[:nq], y[nq:2 * nq], torsion[r])[0]
                    shorten = min(shorten, 0.99 * (-a_old) / (a_new - a_old))
        if shorten < 1.0:
            rejected += 1
            h *= max(shorten, 1e-3)
            continue
        t += h
        y = y_new
        accepted += 1
        k[0, :] = k[6]  # first same as last
        for j in range(nj):
            delta, _, _, _, _, rate, _ = joint_kinematics(y[:nq], y[nq:2 * nq], joints[j])
            if not in_contact[j] and delta > -onset_tol:
                in_contact[j] = True
                speeds[j] = max(rate, speed_floor)
                impacts += 1
                rhs(t, y, k[0], nq, minv, gravity, revolute, prismatic, drive, alpha, joints,
                    speeds, grid_log0, grid_step, tables, torsion, latched, work)
                calls += 1
            elif in_contact[j] and delta < -onset_tol:
                in_contact[j] = False
            depth[j] = delta
        for r in range(torsion.shape[0]):
            if latched[r] == 0.0 and int(torsion[r, 5]) == LATCH and \
                    relative_angle(y[:nq], y[nq:2 * nq], torsion[r])[0] > -LATCH_TOL:
                latched[r] = 1.0
                rhs(t, y, k[0], nq, minv, gravity, revolute, prismatic, drive, alpha, joints,
                    speeds, grid_log0, grid_step, tables, torsion, latched, work)
                calls += 1
        if count == capacity:
            capacity *= 2
            times2 = np.empty(capacity)
            states2 = np.empty((capacity, ny))
            speeds2 = np.empty((capacity, max(nj, 1)))
            times2[:count], states2[:count], speeds2[:count] = times, states, speeds_out
            times, states, speeds_out = times2, states2, speeds2
        times[count], states[count], speeds_out[count, :nj] = t, y, speeds
        count += 1
        factor = 0.9 * err ** -0.14 * err_prev ** 0.08 if err > 0 else 5.0
        h *= min(5.0, max(0.2, factor))
        err_prev = max(err, 1e-4)
    counters = np.array([accepted, rejected, calls, impacts])
    return times[:count], states[:count], speeds_out[:count], counters, status, t
