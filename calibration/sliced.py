r"""Calibrating the sliced law of a finite pin (pinbore.laws.sliced) on 3D FE curves.

A 3D curve gives, per converged step, the hub's approach delta, its tilt theta, the force F
(N) and the tilting moment M (N m) about the bore's mid-plane centre (pinbore.fem.curve). The
sliced law predicts them from a per-length law f (N/m): the 2D-calibrated law of the same
call (`calibrated:<law>`), or a published one. What a plane section cannot know is fitted,
three numbers per group of curves:

    F = a sum_i f_loc(delta_i) w_i,   M = a sum_i f_loc(delta_i) z'_i w_i,
    delta_i = delta - c_b F / L + theta z'_i,   w_i = L/n + e [end slices],   z'_i = z_i - L/2,

f_loc the per-length law with the bulk compliance c_b (m^2/N) taken out (laws/sliced.py):

- c_b, the far field's share of the section's compliance: the housing around a lug moves the
  bore as a whole under the resultant, so the tilt acts on the contact's own compliance only;
- a, a stiffness factor (the 3D body around a slice is not the 2D plane-strain section: free
  ends relax the axial stress);
- e (m), an end length per end (the ends are stiffer or softer than a slice: a flush end of
  pin and bore differs from a pin running on beyond a lug, so the two are fitted apart).

Measured on the shipped study (c/R = 3e-3, flush and overhung lugs 10 and 20 mm long pushed
to 10 um, tilted to 0.15-0.2 deg): with independent slices (c_b = 0) and the exact 2D
section law, F is within 2-5 % but M 30-50 % low, the FE line load running over half the lug
where slices spread it over 80 %; with c_b fitted F is within 5 % and M within 5 %, and
overhung and flush lugs 15 mm long tilted 0.12 deg, not fitted, within 3 % (F and M). The
fitted c_b scales with the housing's compliance: pi E_bore c_b = 2.4 for steel and 2.3 for an
aluminium-alloy housing.

The fit is nonlinear least squares (scipy.optimize.least_squares, trust region within
bounds: a > 0, e above minus half the shortest length, 0 <= c_b below the compliance the
per-length law can give up, laws.tables.largest_compliance) on the relative force error and
on the moment error relative to F L/2 (the resultant's position as a fraction of half the
length: M is zero at theta = 0, where a relative moment error means nothing), 95 % intervals
from the Jacobian at the solution and Student's t.

Curves are grouped by their ends (flush or running on) and materials pair, one law per group:
nothing of different ends or materials is pooled; lengths and tilts are (the end length is
what makes a law of one length carry over to another). The law records the joint its
per-length law was evaluated for (radii, materials, the length the per-length laws take)
and the number of slices of the fit (the end length belongs to it: under tilt the end
slice's approach depends on the slicing). A group whose curves cannot fix the three numbers
(untilted curves of one length: F = a f (L + 2 e) at any c_b) is refused.
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from pinbore.calibration.curves import Curve3D
from pinbore.core.errors import InputError
from pinbore.laws import lawsfile
from pinbore.laws import sliced, tables

FIT_SLICES = 64        # slices while fitting: F within 0.2 % of its limit (laws/sliced.py)
TABLE_POINTS = 400     # of the per-length law's table, over the local approaches of a curve
BULK_BOUND = 0.98      # c_b below this fraction of what the per-length law can give up
BEYOND = 10.0          # the residual of a step the law cannot reach (its table ends)


@dataclass(frozen=True)
class PerLength:
    """The per-length law (N/m) a sliced law is built on: its name (a published law,
    calibrated:<law>, or section: the 2D FE curve of the 3D curve's own plane section), its
    force at approaches d (m) for a 3D curve, force(d, curve), and the record of the section
    it used, section(curve) (None for the other kinds)."""

    name: str
    force: Callable
    section: Callable


def per_length_table(force, curve: Curve3D):
    """(grid_log0, grid_step, table) of the per-length law `force(d, curve)` (N/m) over the
    local approaches the curve reaches: from a thousandth of its smallest approach to ten
    times its largest one at the pin's end (the split law reaches less far: u = delta -
    c_b f(delta))."""
    low = 1e-3 * float(np.min(curve.approach[curve.approach > 0]))
    return tables.tabulate(lambda d: force(d, curve), low, 10 * reach(curve), TABLE_POINTS)


def reach(curve: Curve3D) -> float:
    """The largest approach of a curve at the pin's end (m): delta + |theta| L/2."""
    return float(np.max(curve.approach + np.abs(curve.tilt) * curve.length / 2))


def law_at_steps(curve: Curve3D, table, scale: float, end_length: float, bulk: float,
                 slices: int = FIT_SLICES):
    """F (N) and M (N m) of the sliced law (scale a, end length e (m), bulk compliance c_b
    (m^2/N)) on the per-length law's `table` at every step of the curve."""
    local = tables.split_compliance(*table, bulk)
    relief = curve.relief or (0.0, 0.0)
    rows = np.array([sliced.sliced(d, t, curve.length, slices, *local, *relief, end_length,
                                   scale, bulk)[:2]
                     for d, t in zip(curve.approach, curve.tilt)])
    return rows[:, 0], rows[:, 1]


@dataclass(frozen=True)
class Solution:
    scale: float
    scale_ci95: list[float]
    end_length: float
    end_length_ci95: list[float]
    bulk: float
    bulk_ci95: list[float]
    points: int


class CannotFit(ValueError):
    """The curves of a group cannot fix the stiffness factor, end length and bulk compliance,
    or the per-length law does not reach their approaches."""


def residuals(curves, tables_of, parameters) -> np.ndarray:
    """The fit's residuals at (a, e, c_b): relative force errors at every step, moment errors
    relative to F L/2 at the tilted ones (an untilted step's moment is zero for any a, e, c_b:
    no information)."""
    scale, end_length, bulk = parameters
    out = []
    for c, table in zip(curves, tables_of):
        force, moment = law_at_steps(c, table, scale, end_length, bulk)
        tilted = c.tilt != 0
        out += [force / c.force - 1,
                (moment[tilted] - c.moment[tilted]) / (c.force * c.length / 2)[tilted]]
    # NaN: a slice beyond the per-length law's range at these parameters; a large residual
    # turns the search back (a solution there is refused in `solve`)
    return np.nan_to_num(np.concatenate(out), nan=BEYOND)


def solve(curves, tables_of) -> Solution:
    """a, e and c_b by least squares over every step of `curves` (module docstring). Raises
    CannotFit when the design cannot fix all three: fewer equations than four, or a
    Jacobian whose columns are dependent at the solution (untilted curves of one length)."""
    bulk_most = BULK_BOUND * min(tables.largest_compliance(*t, up_to=reach(c))
                                 for c, t in zip(curves, tables_of))
    shortest = min(c.length for c in curves)
    # the unknowns in units of their expected size: a ~ 1, e ~ 1 mm, c_b ~ half its bound
    unit = np.array([1.0, 1e-3, bulk_most])
    fit = optimize.least_squares(
        lambda x: residuals(curves, tables_of, x * unit), [1.0, 0.0, 0.5],
        bounds=([1e-3, -0.49 * shortest / unit[1], 0.0], [1e3, 10 * shortest / unit[1], 1.0]),
        diff_step=1e-7, x_scale=[0.1, 0.5, 0.1], xtol=1e-12, ftol=1e-12)
    if np.any(fit.fun == BEYOND):
        raise CannotFit("the per-length law does not reach the local approaches of the "
                        "curves (its range ends): choose another (--per-length)")
    jacobian = fit.jac / unit                     # per unit of a, e (m), c_b (m^2/N)
    points = fit.fun.size
    scaled = jacobian * unit
    singular = np.linalg.svd(scaled, compute_uv=False)
    if points < 4 or singular[-1] < 1e-6 * singular[0]:
        raise CannotFit("the curves cannot separate the stiffness factor, the end length "
                        "and the bulk compliance: give tilted steps (load.tilt_deg) and two "
                        "lengths")
    dof = points - 3
    covariance = float(np.sum(fit.fun ** 2)) / dof * np.linalg.inv(jacobian.T @ jacobian)
    half = stats.t.ppf(0.975, dof) * np.sqrt(np.diag(covariance))
    scale, end_length, bulk = fit.x * unit
    return Solution(float(scale), [float(scale - half[0]), float(scale + half[0])],
                    float(end_length), [float(end_length - half[1]), float(end_length + half[1])],
                    float(bulk), [float(max(bulk - half[2], 0.0)), float(bulk + half[2])],
                    int(points))


def predict(curve: Curve3D, law: lawsfile.SlicedLaw, force):
    """F (N) and M (N m) of a calibrated sliced law at the steps of a curve, the per-length
    law `force(d, curve)` (N/m) cut into the fit's FIT_SLICES slices."""
    return law_at_steps(curve, per_length_table(force, curve), law.scale, law.end_length_m,
                        law.bulk_compliance_m2_per_N)


def errors(curve: Curve3D, table, solution: Solution) -> lawsfile.Errors3D:
    """Largest relative errors of the fitted law on a curve: of F, and of M over the tilted
    steps (where M is not zero by symmetry)."""
    force, moment = law_at_steps(curve, table, solution.scale, solution.end_length,
                                 solution.bulk)
    tilted = curve.tilt != 0
    moment_error = (float(np.max(np.abs(moment[tilted] / curve.moment[tilted] - 1)))
                    if tilted.any() else None)
    return lawsfile.Errors3D(force_max_rel=float(np.max(np.abs(force / curve.force - 1))),
                             moment_max_rel=moment_error, points=int(curve.force.size))


def group_key(curve: Curve3D) -> str:
    """The name of a curve's group: its ends and its materials."""
    return f"{'lug' if curve.runs_on else 'flush'}_{curve.materials}"


def calibrate(curves, per_length: PerLength) -> dict[str, lawsfile.SlicedLaw]:
    """One sliced law per group of `curves` (group_key) on the per-length law `per_length`."""
    groups: dict[str, list] = {}
    for c in curves:
        groups.setdefault(group_key(c), []).append(c)
    laws = {}
    for key, members in sorted(groups.items()):
        lengths = sorted({c.length for c in members})
        if len(lengths) < 2:
            raise InputError(f"{', '.join(c.path.as_posix() for c in members)}: 3D group {key}: "
                             f"curves of one length ({lengths[0]:g} m); the end length is what "
                             "carries a sliced law from one length to another, and it needs "
                             "curves of two lengths at least (same ends and materials)")
        table_of = {c.name: per_length_table(per_length.force, c) for c in members}
        tables_of = [table_of[c.name] for c in members]
        try:
            solution = solve(members, tables_of)
        except CannotFit as err:
            raise InputError(f"{', '.join(c.path.as_posix() for c in members)}: 3D group {key}: "
                             f"{err}") from None
        widest = max(members, key=lambda c: float(np.max(np.abs(c.tilt))))
        last = int(np.argmax(np.abs(widest.tilt) + widest.approach / widest.approach.max()))
        needed = sliced.slices_for_force(
            widest.approach[last], widest.tilt[last], widest.length,
            *tables.split_compliance(*table_of[widest.name], solution.bulk),
            *(widest.relief or (0.0, 0.0)), solution.end_length, solution.scale, solution.bulk)
        laws[key] = lawsfile.SlicedLaw(
            model=lawsfile.SLICED_MODEL, per_length_law=per_length.name,
            section=per_length.section(members[0]),
            scale=solution.scale, scale_ci95=solution.scale_ci95,
            end_length_m=solution.end_length, end_length_ci95=solution.end_length_ci95,
            bulk_compliance_m2_per_N=solution.bulk, bulk_compliance_ci95=solution.bulk_ci95,
            ends="running on" if members[0].runs_on else "flush",
            materials=members[0].materials, slices_for_1_percent=int(needed),
            fit_slices=FIT_SLICES, joint=lawsfile.JointRecord.of(members[0].joint),
            points=solution.points,
            validity=lawsfile.Validity3D(
                approach_m=[float(min(c.approach.min() for c in members)),
                            float(max(c.approach.max() for c in members))],
                tilt_rad=[float(min(c.tilt.min() for c in members)),
                          float(max(c.tilt.max() for c in members))],
                length_m=[min(c.length for c in members), max(c.length for c in members)]),
            errors={c.name: errors(c, t, solution) for c, t in zip(members, tables_of)},
            fitted_to=[c.name for c in members])
    return laws
