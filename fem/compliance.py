r"""The surface compliance of a 2D joint's elastic bodies (plane strain, per unit length): how
far a contact pressure opens the gap between pin and bore, the kernel a conformal contact is
solved on (Conformal, below).

A pressure p(theta) per unit of the bore's arc, pressing the pin inward and the bore outward
at the angle theta about the bore's centre (on the pin the same force per radian,
p R_b / R_p per unit of its arc), moves the bodies' surfaces radially, the pin's hub held
and the housing's edge clamped (the FE run's supports). With p interpolated linearly
between angles evenly spaced by Delta, p = sum_j p_j hat_j, the gap at theta_i opens by

    u_bore(theta_i) - u_pin(theta_i) = sum_j C(theta_i - theta_j) p_j,

C the response to the hat of unit height at the load's direction: one solve of the FE's
stiffness (fem.elasticity), read at the surface nodes, interpolated to the angles and made
even (the bodies are round: C depends on the angle between load and point only). Linear
elasticity, small strain: a worn surface shifted by micrometres keeps it.
"""

import csv
import math
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.laws.wearfile import spline

SETTLED = 1e-6   # of the load: the loaded contact's resultant misses it by less
FORCE_FLOOR = 1e-6   # N/m: and by no less than this (the gaps' rounding, 1e-18 m of 1e-2 m)
LEAN_STEP = math.radians(5)   # the push's turns while it brackets the load's direction
BRACKET = 1e-6   # rad: a bracket of the push's direction this narrow closes on a jump
NEWTON = 100   # the most steps of each search (the push, its turn)
FIRST_PUSH = 1e-7   # of the bore's radius: the first push beyond touch
SWAPS, PASSES = 20, 400   # active-set passes changing every sign at once, passes in all
POINTS = 720   # angles around the joint (0.5 degree): the hat's half-width and the kernel's spacing
COLUMNS = ("angle_deg", "compliance_m_per_Pa")


def surface_compliance(el, facet_tags, pin_radius: float, bore_radius: float, direction_deg: float,
                       points: int = POINTS) -> np.ndarray:
    """C at the angle offsets -pi + 2 pi k / points (m/Pa; see the module docstring) of the
    bodies of `el` (fem.elasticity.Elasticity, 2D), the hat centred on `direction_deg` (where
    the mesh is refined)."""
    import dolfinx   # noqa: PLC0415 (the stage that runs DOLFINx)
    import dolfinx.fem.petsc   # noqa: PLC0415
    import ufl   # noqa: PLC0415
    from petsc4py import PETSc   # noqa: PLC0415

    from pinbore.meshes.model import BORE_SURFACE, PIN_SURFACE   # noqa: PLC0415

    mesh = el.mesh
    theta0 = math.radians(direction_deg)
    spacing = 2 * math.pi / points
    x = ufl.SpatialCoordinate(mesh)
    along = math.cos(theta0) * x[0] + math.sin(theta0) * x[1]
    across = -math.sin(theta0) * x[0] + math.cos(theta0) * x[1]
    hat = ufl.max_value(0.0, 1.0 - abs(ufl.atan2(across, along)) / spacing)
    radial = x / ufl.sqrt(ufl.dot(x, x))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    v = ufl.TestFunction(el.V)
    load = dolfinx.fem.form(-hat * (bore_radius / pin_radius) * ufl.dot(radial, v) * ds(PIN_SURFACE)
                            + hat * ufl.dot(radial, v) * ds(BORE_SURFACE))
    b = dolfinx.fem.petsc.assemble_vector(load)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, el.bcs, alpha=0.0)   # the supports held (zero values)
    ksp = PETSc.KSP().create(mesh.comm)
    ksp.setOperators(el.K_bc)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    u = el.K_bc.createVecRight()
    ksp.solve(b, u)
    if ksp.getConvergedReason() < 0:
        raise ArithmeticError(f"the surface compliance's solve failed (PETSc reason {ksp.getConvergedReason()})")
    owned = el.V.dofmap.index_map.size_local
    values = u.getArray(readonly=True).reshape(-1, 2)
    X = el.V.tabulate_dof_coordinates()[:, :2]
    offsets = -math.pi + spacing * np.arange(points)
    opening = np.zeros(points)
    for name, sign in (("bore_surface", 1.0), ("pin_surface", -1.0)):
        dofs = el.dofs[name]
        dofs = dofs[dofs < owned]
        P = X[dofs]
        r = np.linalg.norm(P, axis=1)
        radial_u = np.sum(values[dofs] * P, axis=1) / r
        angle = np.mod(np.arctan2(P[:, 1], P[:, 0]) - theta0 + math.pi, 2 * math.pi) - math.pi
        gathered = mesh.comm.allgather((angle, radial_u))
        angle = np.concatenate([a for a, _ in gathered])
        radial_u = np.concatenate([w for _, w in gathered])
        order = np.argsort(angle)
        opening += sign * np.interp(offsets, angle[order], radial_u[order], period=2 * math.pi)
    for obj in (ksp, u, b):
        obj.destroy()
    return 0.5 * (opening + np.roll(opening[::-1], 1))   # even about the load: C(-a) = C(a)


def write(path: Path, kernel: np.ndarray) -> None:
    """compliance.csv: C (m/Pa) against the angle offset (deg), evenly from -180."""
    angles = -180.0 + 360.0 * np.arange(kernel.size) / kernel.size
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(COLUMNS)
        for a, c in zip(angles, kernel):
            out.writerow([f"{a:.6f}", f"{c:.9e}"])


def read(path) -> np.ndarray:
    """The kernel of a compliance.csv (its angle offsets evenly from -180 degrees); one
    InputError line for a file that is not one."""
    path = Path(path)
    try:
        with open(path, newline="") as f:
            rows = [row for row in csv.reader(f) if row]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"{path}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if not rows or tuple(rows[0]) != COLUMNS:
        raise InputError(f"{path}: the header must be {','.join(COLUMNS)} (run pinbore fem again)")
    try:
        table = np.array([[float(a), float(c)] for a, c in rows[1:]])
    except ValueError:
        raise InputError(f"{path}: a row is not two numbers (run pinbore fem again)") from None
    n = len(table)
    if n < 36 or n % 2 or not np.allclose(table[:, 0], -180.0 + 360.0 * np.arange(n) / n, atol=1e-5) \
            or not np.all(np.isfinite(table[:, 1])) or table[n // 2, 1] <= 0:
        raise InputError(f"{path}: the angles must run evenly from -180 deg (an even number, at "
                         "least 36) with a finite compliance, positive under the load (run pinbore "
                         "fem again)")
    return table[:, 1]


class Conformal:
    """The contact of a worn pin in its worn bore, both elastic, on the surface compliance C
    (`kernel`, m/Pa on POINTS-like even offsets): the pressure p_i (Pa per unit of the bore's
    arc) at the pin's points beta_i (the kernel's angles in the pin's frame), with

        g_i(e) + sum_j C(beta_i - beta_j) p_j >= 0,   p_i >= 0,   p_i (g_i + ...) = 0,

    g_i(e) = r_b(theta_i) - |X_i| the exact gap of the rigid bodies at point i, X_i its
    position r_p(beta_i) u(beta_i + turn) + e from the bore's centre at the angle theta_i,
    the pin's centre at e and turned by `turn` in the bore's frame, r_b = R_b + h_b,
    r_p = R_p - h_p the worn radii (the profiles' Catmull-Rom splines, laws.wearfile). The
    pin pushed to e (`pushed`), or loaded by a force per unit length F' (`loaded`: e where
    the resultant sum_j p_j R_b Delta n_j, n_j = -d g_j / d e, is F' u(direction)). Each
    solve is the primal-dual active set method on the exact gaps at the given e
    (`_solve`); p_i R_b Delta is point i's force (`on_bore`: its pressure on the bore's
    arc)."""

    def __init__(self, kernel: np.ndarray, pin_radius: float, bore_radius: float,
                 bore_depth: np.ndarray, pin_depth: np.ndarray):
        n = kernel.size
        self.n, self.spacing = n, 2 * math.pi / n
        self.by_offset = np.roll(kernel, -(n // 2))   # C at the offset d * spacing, d = 0..n-1
        self.bore_radius, self.bore_depth = bore_radius, np.asarray(bore_depth, float)
        self.beta = -math.pi + self.spacing * np.arange(n)
        self.pin_surface = pin_radius - spline(pin_depth, self.beta)[0]

    def gap(self, e, turn: float, points: np.ndarray):
        """(g_i (m), -d g_i / d e (the gap's closing direction: X_i / |X_i| less the worn
        bore's slope h_b'(theta_i) times d theta_i / d e), theta_i (rad)) at the pin's points
        `points`."""
        b = self.beta[points] + turn
        r = self.pin_surface[points]
        x, y = r * np.cos(b) + e[0], r * np.sin(b) + e[1]
        size = np.hypot(x, y)
        theta = np.arctan2(y, x)
        depth, slope, _ = spline(self.bore_depth, theta)
        turning = slope / size   # d r_b / d theta times |d theta / d e|, along the tangent
        return (self.bore_radius + depth - size,
                np.stack([(x + turning * y) / size, (y - turning * x) / size], axis=1), theta)

    def facing(self, direction: float, turn: float, half_angle: float = math.radians(75)) -> np.ndarray:
        """The pin's points within half_angle of `direction` (rad, the bore's frame)."""
        centre = int(round((direction - turn + math.pi) / self.spacing))
        half = int(half_angle / self.spacing)
        return (centre + np.arange(-half, half + 1)) % self.n

    def pushed(self, e, turn: float, points: np.ndarray):
        """(p, theta) at `points` with the pin's centre at e."""
        g, _, theta = self.gap(np.asarray(e, float), turn, points)
        return self._solve(self.matrix(points), g)[0], theta

    def loaded(self, force: float, direction: float, turn: float):
        """(p, theta, e, R, phi) at the points facing the push under the load per unit length
        `force` (N/m) along `direction` psi*: the pin's centre e where the pressure's resultant
        R = sum_j p_j R_b Delta n_j (n_j = -d g_j / d e) is force u(psi*). The pin is pushed
        from its rigid touch along a direction phi (`pushed_along`) until
        R . u(phi) = force cos(psi* - phi), and phi turned until R's own direction psi(phi)
        is psi* (then |R| = force): a worn joint's pressure leans toward where it conforms,
        the push then off the load. The lean psi(phi) - psi* is bracketed and its root found
        by the Illinois rule; on a rough profile under a light load it jumps where the contact
        moves from one point of the pin to another, and where the bracket closes on such a
        jump the pin rests on both: the two sides' pressures are combined so that their
        resultant lies along psi*, scaled to the force; the push starts along psi* (a
        solution the same whatever else is solved). ArithmeticError where it does not settle."""
        u = np.array([math.cos(direction), math.sin(direction)])
        tolerance = max(SETTLED * force, FORCE_FLOOR)

        def lean(phi):
            out = self.pushed_along(force, direction, phi, turn) + (phi,)
            resultant = out[3]
            return math.remainder(math.atan2(resultant[1], resultant[0]) - direction, 2 * math.pi), out

        def met(out):
            return math.hypot(*(out[3] - force * u)) <= tolerance

        a = direction
        fa, out_a = lean(a)
        if met(out_a):
            return out_a
        b = a - fa   # a round joint leans by the push's turn: d psi / d phi = 1
        for _ in range(NEWTON):   # secant steps until the lean's sign changes
            fb, out_b = lean(b)
            if met(out_b):
                return out_b
            if fb * fa < 0:
                break
            slope = (fb - fa) / (b - a) if b != a else 1.0
            step = -fb / slope if slope > 0 else -math.copysign(LEAN_STEP, fb)
            a, fa, out_a = b, fb, out_b
            b = b + max(-LEAN_STEP, min(LEAN_STEP, step))
        else:
            raise ArithmeticError(f"the load {force:.4g} N/m along {math.degrees(direction):.4g} deg: "
                                  "no push brackets its direction")
        side = 0
        for _ in range(NEWTON):   # Illinois
            c = (a * fb - b * fa) / (fb - fa)
            fc, out_c = lean(c)
            if met(out_c):
                return out_c
            if fc * fb < 0:
                a, fa, out_a = b, fb, out_b
                side = 0
            else:
                fa = 0.5 * fa if side == -1 else fa
                side = -1
            b, fb, out_b = c, fc, out_c
            if abs(b - a) <= BRACKET:   # a jump of the contact's point: resting on both
                return self._resting(force, u, out_a, out_b)
        raise ArithmeticError(f"the load {force:.4g} N/m along {math.degrees(direction):.4g} deg was "
                              f"not met in {NEWTON} turns of the push")

    @staticmethod
    def _resting(force, u, one, other):
        """The pin resting on the contacts of two pushes a hair apart: their pressures
        combined, (1 - w) one + w other, w making the resultant's part across u vanish, then
        scaled to `force` along u."""
        across = np.array([-u[1], u[0]])
        a, b = one[3] @ across, other[3] @ across
        w = a / (a - b)
        resultant = (1 - w) * one[3] + w * other[3]
        scale = force / (resultant @ u)
        return (scale * ((1 - w) * one[0] + w * other[0]), one[1], (1 - w) * one[2] + w * other[2],
                scale * resultant, one[4])

    def pushed_along(self, force: float, direction: float, phi: float, turn: float):
        """(p, theta, e, R) with the pin pushed along u(phi) from its rigid touch e_0,
        e = e_0 + s u, until R . u = force cos(direction - phi): s by Newton's method on
        R . u (its slope the contact's stiffness R_b Delta (N_A u)^T C_AA^-1 (N_A u) on the
        active set A) within a bracket. ArithmeticError where it does not settle, or where
        the contact reaches the ends of the points facing the push."""
        points = self.facing(phi, turn)
        u = np.array([math.cos(phi), math.sin(phi)])
        target = force * math.cos(direction - phi)
        weight = self.bore_radius * self.spacing
        tolerance = max(SETTLED * force, FORCE_FLOOR) * 0.1
        C = self.matrix(points)
        e0 = np.zeros(2)
        for _ in range(3):   # the rigid pin moved along u until its first point touches
            g, normal, _ = self.gap(e0, turn, points)
            ahead = normal @ u > 0.3
            if not ahead.any():
                raise ArithmeticError("no point of the pin faces the push")
            e0 = e0 + u * np.min(g[ahead] / (normal[ahead] @ u))
        low, high, s, active = -math.inf, math.inf, FIRST_PUSH * self.bore_radius, None
        for _ in range(NEWTON):
            g, normal, theta = self.gap(e0 + s * u, turn, points)
            p, active = self._solve(C, g, active)
            N = normal[active]
            resultant = weight * (p[active] @ N)
            miss = target - resultant @ u
            if abs(miss) <= tolerance:
                if p[0] > 0 or p[-1] > 0:
                    raise ArithmeticError("the contact reaches the ends of the points facing the push")
                return p, theta, e0 + s * u, resultant
            low, high = (s, high) if miss > 0 else (low, s)
            along = N @ u
            slope = weight * along @ np.linalg.solve(C[np.ix_(active, active)], along) if along.size else 0.0
            step = s + miss / slope if slope > 0 else math.inf
            if not low < step < high:   # out of the bracket: double it (or back off), or halve it
                if math.isinf(high):
                    step = 2 * abs(s) + FIRST_PUSH * self.bore_radius
                elif math.isinf(low):
                    step = s - 2 * abs(s) - FIRST_PUSH * self.bore_radius
                else:
                    step = 0.5 * (low + high)
            s = step
        raise ArithmeticError(f"the push {target:.4g} N/m was not met in {NEWTON} steps")

    def on_bore(self, p: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The pressure per unit of the bore's arc (Pa) at theta of the solution p at
        consecutive points: point i carries p_i R_b Delta, spread over the bore's arc
        between its neighbours (the pin's points, offset by e, lie closer there than Delta)."""
        return p * self.spacing / np.abs(np.gradient(np.unwrap(theta)))

    def matrix(self, points: np.ndarray) -> np.ndarray:
        """C(beta_i - beta_j) between the pin's points `points`."""
        return self.by_offset[(points[:, None] - points[None, :]) % self.n]

    @staticmethod
    def _solve(C, g, active=None):
        """p >= 0 with g + C p >= 0 complementary (the compliance C between the points, the
        rigid gaps g): (p, the active set), from the active set `active` (default: g < 0);
        every sign change at once (primal-dual active set), then one at a time, the worst
        first, should the set cycle."""
        m = g.size
        active = g < 0 if active is None else active.copy()
        for passes in range(PASSES):
            A = np.flatnonzero(active)
            p = np.zeros(m)
            if A.size:
                p[A] = np.linalg.solve(C[np.ix_(A, A)], -g[A])
            opened = g + C[:, A] @ p[A]
            negative, closed = p < 0, (~active) & (opened < 0)
            if not negative.any() and not closed.any():
                return p, active
            if passes < SWAPS:
                active = (active & ~negative) | closed
            elif negative.any():
                active[np.argmin(np.where(negative, p, np.inf))] = False
            else:
                active[np.argmin(np.where(closed, opened, np.inf))] = True
        raise ArithmeticError(f"the conformal contact's active set did not settle in {PASSES} passes")
