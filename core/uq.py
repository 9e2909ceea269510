"""Uncertainty quantification: input distributions, sampling plans, statistics with confidence
intervals, exceedance probabilities, Sobol sensitivity indices and the tolerance band of a
uniform parameter. numpy and scipy only: no model, no file.

Sampling (`plan`): points in the unit hypercube of the parameters, mapped through each
distribution's inverse CDF: `monte_carlo` (independent draws: the binomial bounds below hold
exactly), `lhs` (Latin hypercube), `sobol` (scrambled Sobol' sequence), `saltelli` (the
2 + d blocks A, B, AB_i of Saltelli 2010 for Sobol indices; N (d + 2) points) and `grid` (every
combination of each parameter's values).

Statistics (`describe`): the mean with its Student-t interval; the standard deviation with its
chi-square interval (normal data); quantiles with their distribution-free order-statistic
interval; an exceedance probability P(Y > threshold) with its Clopper-Pearson (exact binomial)
interval.

Sobol indices (`sobol`): first order by the Saltelli 2010 estimator
S_i = mean(f_B (f_ABi - f_A)) / V, total order by Jansen's ST_i = mean((f_A - f_ABi)^2) / (2 V),
with V the variance of f_A and f_B pooled; their confidence intervals by bootstrap (resampling
the N rows of the blocks together), percentile intervals.

Why no library: SALib 1.6 gives the same estimators (its Ishigami errors at N = 1024 and 8192:
S1 0.0041 and 0.0013, ST 0.0014 and 0.0002, the same order as here), but importing it takes
2.0 s (it loads pandas) and adds pandas, multiprocess and dill to the environment; OpenTURNS and
chaospy are larger still. scipy.stats.qmc already has the Sobol' and Latin-hypercube
generators, and the estimators are a few lines of numpy, checked against the Ishigami
function's closed form (tests/test_study.py).

Surrogate (`chaos`): a polynomial chaos expansion of the output in the inputs, fitted by least
squares on any random plan: each input u_i = F_i(x_i) (its CDF: every input uniform on [0, 1],
any distribution) mapped to z_i = 2 u_i - 1 and expanded in Legendre polynomials, orthogonal
for the uniform measure, P_n with E[P_n^2] = 1/(2n + 1), over the multi-indices of total
degree <= p. Mean, variance and Sobol indices follow from the coefficients [Sudret2008]:
mean c_0, V = sum_{a != 0} c_a^2 / prod(2 a_i + 1), S_i the share of the terms in z_i alone,
ST_i of the terms that hold z_i. Its accuracy: the leave-one-out error of the least-squares fit
(exact from the hat matrix, no refit), relative to the output's variance; a degree is refused
when the plan has fewer than twice as many points as terms. It pays where a point costs
seconds (FE, impacts): the Ishigami function's indices within 1e-5 from 1000 points at degree
12, where Saltelli's estimators need 5 x 16384 runs for 1e-3.

Tolerance (`tolerance_band`): a uniform parameter sampled over its widest band
[centre - H, centre + H] by independent draws; the points inside a narrower band
[centre - h, centre + h] are independent uniform draws over that band (rejection sampling, the
other parameters unchanged), so every narrower band is answered by the same runs: no new run,
no weights. The band holds when the one-sided Clopper-Pearson upper bound of its exceedance
probability is at most the target; the answer is the largest such h (scanned at every sampled
half-width, where the count changes).
"""

import math
import warnings
from typing import NamedTuple

import numpy as np

METHODS = ("grid", "monte_carlo", "lhs", "sobol", "saltelli")


def distribution(kind: str, **p) -> "scipy.stats.rv_continuous":
    """The frozen scipy distribution of an input: uniform (low, high), normal (mean, std),
    lognormal (median, sigma: the standard deviation of ln Y), truncnormal (mean, std, low,
    high)."""
    from scipy import stats   # noqa: PLC0415 (loaded when used)

    if kind == "uniform":
        return stats.uniform(loc=p["low"], scale=p["high"] - p["low"])
    if kind == "normal":
        return stats.norm(loc=p["mean"], scale=p["std"])
    if kind == "lognormal":
        return stats.lognorm(s=p["sigma"], scale=p["median"])
    if kind == "truncnormal":
        a, b = (p["low"] - p["mean"]) / p["std"], (p["high"] - p["mean"]) / p["std"]
        return stats.truncnorm(a, b, loc=p["mean"], scale=p["std"])
    raise ValueError(f"unknown distribution {kind!r}")


def unit_plan(method: str, dims: int, points: int, seed: int) -> np.ndarray:
    """`points` rows in [0, 1)^dims (saltelli: `points` base rows, N (dims + 2) in all, in the
    blocks A, B, AB_1 .. AB_dims)."""
    from scipy.stats import qmc   # noqa: PLC0415 (loaded when used)

    if method == "monte_carlo":
        return np.random.default_rng(seed).random((points, dims))
    if method == "lhs":
        return qmc.LatinHypercube(d=dims, seed=seed).random(points)
    if method == "sobol":
        return _sobol(dims, points, seed)
    if method == "saltelli":
        base = _sobol(2 * dims, points, seed)
        a, b = base[:, :dims], base[:, dims:]
        blocks = [a, b]
        for i in range(dims):
            ab = a.copy()
            ab[:, i] = b[:, i]
            blocks.append(ab)
        return np.vstack(blocks)
    raise ValueError(f"unknown sampling method {method!r}")


def _sobol(dims: int, points: int, seed: int) -> np.ndarray:
    """A scrambled Sobol' sequence's first `points` points (balanced at powers of 2)."""
    from scipy.stats import qmc   # noqa: PLC0415 (loaded when used)

    with warnings.catch_warnings():   # scipy warns when `points` is no power of 2
        warnings.simplefilter("ignore", UserWarning)
        return qmc.Sobol(d=dims, scramble=True, seed=seed).random(points)


def plan(method: str, dists: list, points: int, seed: int) -> np.ndarray:
    """Sample points (one row each, one column per distribution) of a random plan."""
    u = unit_plan(method, len(dists), points, seed)
    return np.column_stack([d.ppf(u[:, j]) for j, d in enumerate(dists)])


def grid(values: list[list[float]]) -> np.ndarray:
    """Every combination of each parameter's values (the last parameter varies fastest)."""
    mesh = np.meshgrid(*[np.asarray(v, dtype=float) for v in values], indexing="ij")
    return np.column_stack([m.ravel() for m in mesh])


# ---- intervals

def chi2_quantile(q: float, dof: int) -> float:
    """The q-quantile of the chi-square law of dof degrees of freedom: 2 P^-1(dof / 2, q), P
    the regularised lower incomplete gamma function."""
    from scipy import special   # noqa: PLC0415 (loaded when used)

    return 2.0 * float(special.gammaincinv(dof / 2, q))


def mean_interval(y, confidence: float) -> tuple[float, float, float]:
    """The sample mean and its two-sided Student-t interval."""
    from scipy import special   # noqa: PLC0415 (loaded when used; scipy.stats costs 0.6 s more)

    y = np.asarray(y, dtype=float)
    n, mean = len(y), float(np.mean(y))
    if n < 2:
        return mean, math.nan, math.nan
    half = special.stdtrit(n - 1, 0.5 + confidence / 2) * np.std(y, ddof=1) / math.sqrt(n)
    return mean, mean - half, mean + half


def std_interval(y, confidence: float) -> tuple[float, float, float]:
    """The sample standard deviation and its chi-square interval (exact for normal data)."""
    y = np.asarray(y, dtype=float)
    n = len(y)
    if n < 2:
        return math.nan, math.nan, math.nan
    s2, alpha = float(np.var(y, ddof=1)), 1 - confidence
    low = (n - 1) * s2 / chi2_quantile(1 - alpha / 2, n - 1)
    high = (n - 1) * s2 / chi2_quantile(alpha / 2, n - 1)
    return math.sqrt(s2), math.sqrt(low), math.sqrt(high)


def clopper_pearson(k: int, n: int, confidence: float, side: str = "two-sided") -> tuple[float, float]:
    """The exact binomial interval of a probability from k successes in n trials: two-sided,
    or one-sided "upper" ((0, high]) or "lower" ([low, 1))."""
    from scipy import special   # noqa: PLC0415 (loaded when used)

    alpha = 1 - confidence if side != "two-sided" else (1 - confidence) / 2
    low = 0.0 if k == 0 or side == "upper" else float(special.betaincinv(k, n - k + 1, alpha))
    high = 1.0 if k == n or side == "lower" else float(special.betaincinv(k + 1, n - k, 1 - alpha))
    return low, high


def quantile_interval(y, p: float, confidence: float) -> tuple[float, float, float]:
    """The p-quantile and its distribution-free interval between two order statistics:
    the number of samples below the true quantile is Binomial(n, p), so
    [Y_(l), Y_(u)] covers it with probability >= confidence (nan where n is too small)."""
    from scipy import special   # noqa: PLC0415 (loaded when used)

    y = np.sort(np.asarray(y, dtype=float))
    n = len(y)
    q = float(np.quantile(y, p))
    cdf = special.bdtr(np.arange(n + 1), n, p)   # P(B <= k), B ~ Binomial(n, p)
    alpha = (1 - confidence) / 2

    def ppf(level):   # the least k with P(B <= k) >= level
        return int(np.searchsorted(cdf, level * (1 - 1e-12)))

    lo = ppf(alpha)              # P(B <= lo - 1) <= alpha
    hi = ppf(1 - alpha) + 1      # P(B >= hi) <= alpha
    low = y[lo - 1] if lo >= 1 else math.nan
    high = y[hi - 1] if hi <= n else math.nan
    return q, float(low), float(high)


class Exceedance(NamedTuple):
    probability: float
    low: float
    high: float
    exceeding: int
    points: int


def exceedance(y, threshold: float, confidence: float) -> Exceedance:
    """P(Y > threshold): the fraction of the samples above it and its Clopper-Pearson interval."""
    y = np.asarray(y, dtype=float)
    k, n = int(np.sum(y > threshold)), len(y)
    return Exceedance(k / n, *clopper_pearson(k, n, confidence), k, n)


def exceedance_curve(y, confidence: float) -> np.ndarray:
    """Rows (threshold, P(Y > threshold), CP low, CP high) at every sorted sample."""
    y = np.sort(np.asarray(y, dtype=float))
    n = len(y)
    above = n - np.searchsorted(y, y, side="right")
    rows = [(t, k / n, *clopper_pearson(int(k), n, confidence)) for t, k in zip(y, above)]
    return np.array(rows)


def describe(y, confidence: float) -> dict:
    """Count, mean, standard deviation, extremes and 5/50/95 % quantiles, each estimate with
    its confidence interval (see the module)."""
    y = np.asarray(y, dtype=float)
    mean, mlo, mhi = mean_interval(y, confidence)
    std, slo, shi = std_interval(y, confidence)
    out = {"points": int(len(y)), "confidence": confidence,
           "mean": mean, "mean_interval": [mlo, mhi],
           "std": std, "std_interval": [slo, shi],
           "min": float(np.min(y)), "max": float(np.max(y))}
    for p in (0.05, 0.5, 0.95):
        q, lo, hi = quantile_interval(y, p, confidence)
        out[f"q{round(100 * p):02d}"] = q
        out[f"q{round(100 * p):02d}_interval"] = [lo, hi]
    return out


# ---- Sobol indices

def sobol(y, dims: int, confidence: float = 0.95, resamples: int = 1000, seed: int = 0) -> dict:
    """First- and total-order Sobol indices from the outputs of a saltelli plan (the blocks
    A, B, AB_1 .. AB_d of N rows each, in that order), with bootstrap percentile intervals."""
    y = np.asarray(y, dtype=float)
    n = len(y) // (dims + 2)
    if n * (dims + 2) != len(y):
        raise ValueError(f"{len(y)} outputs are no saltelli plan of {dims} parameters")
    blocks = y.reshape(dims + 2, n)
    first, total = _indices(blocks)
    rng = np.random.default_rng(seed)
    boot = [_indices(blocks[:, rng.integers(0, n, n)]) for _ in range(resamples)]
    bf, bt = np.array([b[0] for b in boot]), np.array([b[1] for b in boot])
    tail = 100 * (1 - confidence) / 2
    return {"points_per_block": n, "first": first, "total": total,
            "first_interval": np.percentile(bf, [tail, 100 - tail], axis=0).T,
            "total_interval": np.percentile(bt, [tail, 100 - tail], axis=0).T}


def _indices(blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Saltelli's first-order and Jansen's total-order estimators on the outputs centred on
    the mean of A and B: the first-order one, mean(f_B (f_ABi - f_A)), has the square of the
    outputs' mean in its variance (f_ABi - f_A averages to zero but scatters); centring leaves
    its expectation and removes that term (a quantity whose scatter is 8 % of its mean had
    first-order intervals 3 wide at N = 128 uncentred)."""
    blocks = blocks - np.mean(blocks[:2])
    f_a, f_b, f_ab = blocks[0], blocks[1], blocks[2:]
    var = np.var(np.concatenate([f_a, f_b]))
    first = np.mean(f_b * (f_ab - f_a), axis=1) / var
    total = 0.5 * np.mean((f_a - f_ab) ** 2, axis=1) / var
    return first, total


# ---- tolerance

def tolerance_band(x, y, centre: float, widest: float, threshold: float, target: float,
                   confidence: float) -> dict:
    """The largest half-width h <= widest of the band [centre - h, centre + h] of a uniform
    parameter x (sampled independently over the widest band) such that the one-sided
    Clopper-Pearson upper bound on P(y > threshold) over the points inside the band is at most
    `target`; the bound at each sampled half-width as a curve. None when no band holds."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    distance = np.abs(x - centre)
    order = np.argsort(distance)
    above = np.cumsum(y[order] > threshold)
    curve, best = [], None
    for m in range(len(order)):
        if m + 1 < len(order) and distance[order[m + 1]] == distance[order[m]]:
            continue   # a band holds every point at its edge
        n, k = m + 1, int(above[m])
        bound = clopper_pearson(k, n, confidence, "upper")[1]
        h = float(distance[order[m]])
        curve.append((h, n, k, bound))
        if bound <= target:
            best = (h, n, k, bound)
    return {"half_width": None if best is None else best[0],
            "points_in_band": None if best is None else best[1],
            "exceeding_in_band": None if best is None else best[2],
            "upper_bound": None if best is None else best[3],
            "widest_half_width": widest,
            "fewest_points_needed": math.ceil(math.log(1 - confidence) / math.log(1 - target)),
            "curve": curve}


# ---- surrogate: polynomial chaos

def multi_indices(dims: int, degree: int) -> np.ndarray:
    """Every multi-index a of `dims` non-negative integers with sum(a) <= degree, the zero
    index first, then by total degree."""
    out = [a for a in np.ndindex(*(degree + 1,) * dims) if sum(a) <= degree]
    return np.array(sorted(out, key=lambda a: (sum(a), tuple(-v for v in a))), dtype=int)


def legendre_basis(z: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The products prod_i P_{a_i}(z_i) of Legendre polynomials at the points z (n, dims) in
    [-1, 1]^dims, one column per multi-index (Bonnet's recursion)."""
    degree = int(indices.max(initial=0))
    p = np.ones((degree + 1,) + z.shape)
    if degree >= 1:
        p[1] = z
    for n in range(1, degree):
        p[n + 1] = ((2 * n + 1) * z * p[n] - n * p[n - 1]) / (n + 1)
    columns = np.ones((z.shape[0], len(indices)))
    for i in range(z.shape[1]):
        columns *= p[indices[:, i], :, i].T
    return columns


class Chaos(NamedTuple):
    """A fitted polynomial chaos expansion (`chaos`)."""

    indices: np.ndarray        # (terms, dims) multi-indices
    coefficients: np.ndarray   # (terms,)
    mean: float
    variance: float
    first: np.ndarray          # (dims,) first-order Sobol indices
    total: np.ndarray          # (dims,) total-order Sobol indices
    loo_error: float           # leave-one-out mean square error / the output's variance

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """The surrogate at points u (n, dims) of the unit hypercube (the inputs' CDF values)."""
        return legendre_basis(2 * np.asarray(u, float) - 1, self.indices) @ self.coefficients


def chaos(u, y, degree: int) -> Chaos:
    """The Legendre chaos of total degree `degree` fitted by least squares to the outputs y at
    the points u (n, dims) of the unit hypercube (each input's CDF value: the plan's own
    points); ValueError when the plan has fewer than twice as many points as terms."""
    u, y = np.asarray(u, float), np.asarray(y, float)
    indices = multi_indices(u.shape[1], degree)
    if len(y) < 2 * len(indices):
        raise ValueError(f"a chaos of degree {degree} in {u.shape[1]} inputs has {len(indices)} "
                         f"terms: it needs at least {2 * len(indices)} points (given {len(y)})")
    basis = legendre_basis(2 * u - 1, indices)
    q, r = np.linalg.qr(basis)
    coefficients = np.linalg.solve(r, q.T @ y)
    residual = y - basis @ coefficients
    leverage = np.sum(q**2, axis=1)
    loo = float(np.mean((residual / (1 - leverage)) ** 2) / max(np.var(y), 1e-300))
    norms = 1 / np.prod(2 * indices + 1, axis=1)
    share = coefficients**2 * norms
    variance = float(share[1:].sum())
    alone = [(indices[:, i] > 0) & (indices.sum(axis=1) == indices[:, i]) for i in range(u.shape[1])]
    held = [indices[:, i] > 0 for i in range(u.shape[1])]
    scale = max(variance, 1e-300)
    return Chaos(indices, coefficients, float(coefficients[0]), variance,
                 np.array([share[m].sum() / scale for m in alone]),
                 np.array([share[m].sum() / scale for m in held]), loo)

