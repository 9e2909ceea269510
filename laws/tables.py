"""Force laws as tables: log f on a uniform grid of log delta, and the lookup (the compiled
core's, which the multibody engine calls).

A law f(delta) (a force, N, or a force per unit length, N/m; the table does not care) is
tabulated as table_j = ln f(delta_j) at delta_j = exp(grid_log0 + j grid_step), j = 0..m-1.
Between grid points ln f is linear in ln delta, so on each segment f is the power law through
its two ends: exact for a power law f = K delta^n anywhere, and for any smooth law the error
is of order grid_step^2 times the change of the local exponent. Below the grid the first
segment's power law continues to delta -> 0; above the grid, or where the table holds NaN
(a law beyond its range), the lookup gives NaN, so a caller sees a law used outside what was
tabulated instead of a silent number.
"""

import math

import numpy as np

from pinbore.core.cpp import laws as _core

# f(delta) and (f, df/d delta) at delta > 0 from `table` = ln f on the grid ln delta_j =
# grid_log0 + j grid_step: log-log interpolation, the power law of the first segment below
# the grid, NaN above it or where the table is NaN; on a segment f = f_i (delta/delta_i)^s,
# s = (table_i+1 - table_i) / grid_step, so df/d delta = s f / delta (cpp/mechanism/laws.h:
# the lookup the multibody engine makes)
table_force = _core.table_force
table_force_slope = _core.table_force_slope


def log_grid(d_low: float, d_high: float, points: int):
    """The grid of `table_force` from d_low to d_high (m), `points` points uniform in
    ln delta: (grid_log0, grid_step, the approaches delta_j)."""
    grid_log0 = math.log(d_low)
    grid_step = (math.log(d_high) - grid_log0) / (points - 1)
    return grid_log0, grid_step, np.exp(grid_log0 + grid_step * np.arange(points))


def tabulate(law, d_low: float, d_high: float, points: int):
    """(grid_log0, grid_step, table) of the law `law`, a callable taking an array of
    approaches (m) and returning f (> 0 on the grid; NaN where the law does not hold), for
    `table_force` over [d_low, d_high]."""
    grid_log0, grid_step, deltas = log_grid(d_low, d_high, points)
    return grid_log0, grid_step, np.log(np.asarray(law(deltas), float))


def split_compliance(grid_log0, grid_step, table, compliance: float):
    """The table of the law that remains when a linear compliance is taken out of a tabulated
    law: given f(delta) (the table), the law f(u) with

        delta = u + compliance f     (compliance in m per unit of f, e.g. m^2/N for N/m),

    on a uniform grid of ln u over the same number of points. u(delta) grows as long as
    compliance f'(delta) < 1; where it stops growing (a stiffening law is stiffer there than
    the compliance taken out of it) or the table turns NaN (the law's range ends), the new
    table ends: its lookup gives NaN beyond. Raises ValueError when not even the first two
    points remain."""
    finite = int(np.argmin(np.isfinite(table))) if not np.all(np.isfinite(table)) else table.size
    deltas = np.exp(grid_log0 + grid_step * np.arange(finite))
    f = np.exp(table[:finite])
    u = deltas - compliance * f
    rising = np.flatnonzero(np.diff(u) <= 0)
    end = int(rising[0]) + 1 if rising.size else u.size
    if end < 2 or u[0] <= 0:
        raise ValueError(f"a compliance of {compliance:.4g} is more than the law's own "
                         "(delta - compliance f(delta) must grow with delta)")
    new_log0, new_step, grid = log_grid(u[0], u[end - 1], table.size)
    return new_log0, new_step, np.interp(np.log(grid), np.log(u[:end]), table[:end])


def largest_compliance(grid_log0, grid_step, table, up_to: float = math.inf) -> float:
    """The compliance split_compliance can take out of a tabulated law up to the approach
    `up_to` (m): 1 / max f'(delta) there (the secant slopes between the table's points)."""
    deltas = np.exp(grid_log0 + grid_step * np.arange(table.size))
    slopes = np.diff(np.exp(table)) / np.diff(deltas)
    return float(1.0 / np.nanmax(slopes[deltas[:-1] <= up_to]))
