r"""Calibrating the sliced law of a finite pin (pinbore.laws.sliced) on 3D FE curves.

A 3D curve gives, per converged step, the hub's approach delta, its tilt theta, the force F
(N) and the tilting moment M (N m) about the bore's mid-plane centre (pinbore.fem.curve). The
sliced law predicts them from a per-length law f (N/m): the 2D-calibrated law of the same
call (`calibrated:<law>`), or a published one. What a plane section cannot know is fitted:

    F = a [ sum_i f(delta_i) L/n + e (f_0 + f_{n-1}) ],
    M = a [ sum_i f(delta_i) z'_i L/n + e (f_0 z'_0 + f_{n-1} z'_{n-1}) ],   z'_i = z_i - L/2,

a stiffness factor a (the 3D body around a slice is not the 2D plane-strain section: free
ends relax the axial stress) and an end length e (m) per end (the ends are stiffer or softer
than a slice: a flush end of pin and bore differs from a pin running on beyond a lug, so the
two are fitted apart). With b = a e the model is linear in (a, b): ordinary least squares on
the relative force error and on the moment error relative to F L/2 (the resultant's position
as a fraction of half the length: M is zero at theta = 0, where a relative moment error
means nothing), in closed form, 95 % intervals from Student's t; e = b/a with its interval by
the delta method.

Curves are grouped by their ends (flush or running on) and materials pair, one law per group:
nothing of different ends or materials is pooled; lengths and tilts are (the end length is
what makes a law of one length carry over to another). The law records the joint its
per-length law was evaluated for (radii, materials, the length the per-length laws take)
and the number of slices of the fit (the end length belongs to it: under tilt the end
slice's approach depends on the slicing). A group without tilted steps and of one length
cannot separate a from e and is refused.
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from pinbore.calibration import lawsfile
from pinbore.calibration.curves import Curve3D
from pinbore.core.errors import InputError
from pinbore.laws import sliced, tables

FIT_SLICES = 64        # slices while fitting: F within 0.2 % of its limit (laws/sliced.py)
TABLE_POINTS = 400     # of the per-length law's table, over the local approaches of a curve


def per_length_table(force, curve: Curve3D):
    """(grid_log0, grid_step, table) of the per-length law `force(d, joint)` (N/m) over the
    local approaches the curve reaches: from a thousandth of its smallest approach to its
    largest one at the pin's end, with margin."""
    reach = float(np.max(curve.approach + np.abs(curve.tilt) * curve.length / 2))
    low = 1e-3 * float(np.min(curve.approach[curve.approach > 0]))
    return tables.tabulate(lambda d: force(d, curve.joint), low, 2 * reach, TABLE_POINTS)


def basis(curve: Curve3D, table, slices: int = FIT_SLICES) -> np.ndarray:
    """(points, 4): the sliced F and M at end length 0, and their change per metre of end
    length (f_0 + f_{n-1} and its moment), at every step of the curve."""
    rows = []
    relief = curve.relief or (0.0, 0.0)
    for d, t in zip(curve.approach, curve.tilt):
        bare = sliced.sliced(d, t, curve.length, slices, *table, *relief, 0.0)
        unit = sliced.sliced(d, t, curve.length, slices, *table, *relief, 1.0)
        rows.append((bare[0], bare[1], unit[0] - bare[0], unit[1] - bare[1]))
    return np.array(rows)


@dataclass(frozen=True)
class Solution:
    scale: float
    scale_ci95: list[float]
    end_length: float
    end_length_ci95: list[float]
    points: int


class NotSeparable(ValueError):
    """The curves of a group cannot tell the stiffness factor from the end length."""


def solve(curves, bases) -> Solution:
    """a and e by least squares over every step of `curves` (module docstring): the force of
    every step, the moment of the tilted ones (an untilted step's moment is zero for any a,
    e: no information). Raises NotSeparable when the design cannot fix both: untilted
    curves of one length give F = a f (L + 2 e), a and e only through that product."""
    design, target = [], []
    for c, m in zip(curves, bases):
        tilted = c.tilt != 0
        moment_scale = (c.force * c.length / 2)[tilted]
        design += [np.column_stack([m[:, 0], m[:, 2]]) / c.force[:, None],
                   np.column_stack([m[tilted, 1], m[tilted, 3]]) / moment_scale[:, None]]
        target += [np.ones_like(c.force), c.moment[tilted] / moment_scale]
    x, y = np.vstack(design), np.concatenate(target)
    singular = np.linalg.svd(x, compute_uv=False)
    if y.size < 3 or singular[-1] < 1e-8 * singular[0]:
        raise NotSeparable("the curves cannot separate the stiffness factor from the end "
                           "length: give tilted steps (load.tilt_deg) or two lengths")
    dof = y.size - 2
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    covariance = float(np.sum((y - x @ coef) ** 2)) / max(dof, 1) * np.linalg.inv(x.T @ x)
    t = stats.t.ppf(0.975, max(dof, 1))
    a, b = coef
    e = b / a
    gradient = np.array([-b / a**2, 1 / a])   # of e = b / a
    half_e = t * math.sqrt(float(gradient @ covariance @ gradient))
    half_a = t * math.sqrt(covariance[0, 0])
    return Solution(float(a), [float(a - half_a), float(a + half_a)], float(e),
                    [float(e - half_e), float(e + half_e)], int(y.size))


def predicted(basis_rows, scale: float, end_length: float):
    """The fitted law's F (N) and M (N m) at the steps of a basis."""
    return (scale * (basis_rows[:, 0] + end_length * basis_rows[:, 2]),
            scale * (basis_rows[:, 1] + end_length * basis_rows[:, 3]))


def predict(curve: Curve3D, law: lawsfile.SlicedLaw, force):
    """F (N) and M (N m) of a calibrated sliced law at the steps of a curve, the per-length
    law `force(d, joint)` (N/m) cut into the fit's FIT_SLICES slices."""
    rows = basis(curve, per_length_table(force, curve))
    return predicted(rows, law.scale, law.end_length_m)


def errors(curve: Curve3D, basis_rows, solution: Solution) -> lawsfile.Errors3D:
    """Largest relative errors of the fitted law on a curve: of F, and of M over the tilted
    steps (where M is not zero by symmetry)."""
    force, moment = predicted(basis_rows, solution.scale, solution.end_length)
    tilted = curve.tilt != 0
    moment_error = (float(np.max(np.abs(moment[tilted] / curve.moment[tilted] - 1)))
                    if tilted.any() else None)
    return lawsfile.Errors3D(force_max_rel=float(np.max(np.abs(force / curve.force - 1))),
                             moment_max_rel=moment_error, points=int(curve.force.size))


def group_key(curve: Curve3D) -> str:
    """The name of a curve's group: its ends and its materials."""
    return f"{'lug' if curve.runs_on else 'flush'}_{curve.materials}"


def calibrate(curves, per_length_name: str, force) -> dict[str, lawsfile.SlicedLaw]:
    """One sliced law per group of `curves` (group_key) with the per-length law `force(d,
    joint)` (N/m) named `per_length_name`."""
    groups: dict[str, list] = {}
    for c in curves:
        groups.setdefault(group_key(c), []).append(c)
    laws = {}
    for key, members in sorted(groups.items()):
        table_of = {c.name: per_length_table(force, c) for c in members}
        bases = [basis(c, table_of[c.name]) for c in members]
        try:
            solution = solve(members, bases)
        except NotSeparable as err:
            raise InputError(f"{', '.join(c.path.as_posix() for c in members)}: 3D group {key}: "
                             f"{err}") from None
        widest = max(members, key=lambda c: float(np.max(np.abs(c.tilt))))
        last = int(np.argmax(np.abs(widest.tilt) + widest.approach / widest.approach.max()))
        needed = sliced.slices_for_force(widest.approach[last], widest.tilt[last], widest.length,
                                         *table_of[widest.name], *(widest.relief or (0.0, 0.0)),
                                         solution.end_length)
        laws[key] = lawsfile.SlicedLaw(
            model=lawsfile.SLICED_MODEL, per_length_law=per_length_name,
            scale=solution.scale, scale_ci95=solution.scale_ci95,
            end_length_m=solution.end_length, end_length_ci95=solution.end_length_ci95,
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
            errors={c.name: errors(c, b, solution) for c, b in zip(members, bases)},
            fitted_to=[c.name for c in members])
    return laws
