"""Force laws as tables: log f on a uniform grid of log delta, and the compiled lookup.

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

import numba
import numpy as np


@numba.njit(cache=True)
def table_force(delta, grid_log0, grid_step, table):
    """f(delta) (units of the tabulated law) for delta > 0 from `table` = ln f on the grid
    ln delta_j = grid_log0 + j grid_step: log-log interpolation, the power law of the first
    segment below the grid, NaN above it or where the table is NaN."""
    x = (math.log(delta) - grid_log0) / grid_step
    if x > table.size - 1 or not math.isfinite(table[min(max(int(x) + 1, 0), table.size - 1)]):
        return math.nan
    i = min(max(int(math.floor(x)), 0), table.size - 2)
    return math.exp(table[i] + (x - i) * (table[i + 1] - table[i]))


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
