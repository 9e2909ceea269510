"""A study's statistics over its complete points (pinbore.core.uq): each quantity's
description, the limit's exceedance, Sobol indices of a Saltelli plan, the polynomial chaos
surrogates and the tolerance band."""

import json
import math

import numpy as np

from pinbore.core import uq
from pinbore.study.plan import Plan


def complete(rows, name) -> np.ndarray:
    return np.array([r[name] for r in rows if r["status"] == "complete"], dtype=float)


def sampled(plan: Plan, rows: list[dict]) -> list[dict]:
    """The rows the statistics and their figures take: every point, but of a Saltelli plan
    only the blocks A and B (its blocks AB_i repeat their coordinates, and the intervals count
    independent draws)."""
    return rows[:2 * plan.study.sampling.points] if plan.study.sampling.method == "saltelli" else rows


def statistics(plan: Plan, rows: list[dict]) -> dict:
    """Per quantity: uq.describe over the complete points; the limit's exceedance; Sobol
    indices for a saltelli plan (every point must be complete: a hole breaks the blocks)."""
    study, conf = plan.study, plan.study.confidence
    out = {"confidence": conf, "method": study.sampling.method,
           "complete_points": sum(r["status"] == "complete" for r in rows), "points": len(rows),
           "quantities": {}}
    sample = sampled(plan, rows)
    if study.sampling.method == "saltelli":
        out["statistics_of"] = "the A and B blocks of the Saltelli plan"
    for c in study.collect:
        y = complete(sample, c.name)
        out["quantities"][c.name] = uq.describe(y, conf) if len(y) else {"points": 0}
    if study.limit is not None and out["complete_points"]:
        lim = study.limit
        e = uq.exceedance(complete(sample, lim.quantity), lim.threshold, conf)
        upper = uq.clopper_pearson(e.exceeding, e.points, conf, "upper")[1]
        out["limit"] = {"quantity": lim.quantity, "threshold": lim.threshold, "target": lim.target,
                        "probability": e.probability, "interval": [e.low, e.high],
                        "exceeding": e.exceeding, "points": e.points, "upper_bound": upper,
                        "meets_target": upper <= lim.target}
    if study.surrogate is not None:
        out["surrogate"] = surrogates(plan, rows)
    if study.sampling.method == "saltelli":
        out["sobol"] = {}
        if out["complete_points"] == len(rows):
            for c in study.collect:
                s = uq.sobol([r[c.name] for r in rows], len(plan.names), conf, seed=study.sampling.seed)
                out["sobol"][c.name] = {
                    name: {"first": s["first"][j], "first_interval": s["first_interval"][j].tolist(),
                           "total": s["total"][j], "total_interval": s["total_interval"][j].tolist()}
                    for j, name in enumerate(plan.names)}
        else:
            out["sobol_missing"] = "not every point completed: the Saltelli blocks have holes"
    return json.loads(json.dumps(out, default=float))


def surrogates(plan: Plan, rows: list[dict]) -> dict:
    """Per quantity, the polynomial chaos (core.uq.chaos) of the complete points, each
    parameter's value mapped to the unit interval by its distribution's CDF: the leave-one-out
    error (of the variance), mean, standard deviation and Sobol indices by parameter."""
    dists = [p.distribution.frozen() for p in plan.study.parameters.values()]
    done = [i for i, r in enumerate(rows) if r["status"] == "complete"]
    u = np.column_stack([d.cdf(plan.values[done, j]) for j, d in enumerate(dists)])
    out = {}
    for c in plan.study.collect:
        y = np.array([rows[i][c.name] for i in done], dtype=float)
        try:
            fit = uq.chaos(u, y, plan.study.surrogate.degree)
        except ValueError as err:
            out[c.name] = {"missing": str(err)}
            continue
        out[c.name] = {"degree": plan.study.surrogate.degree, "terms": len(fit.indices),
                       "points": len(y), "loo_error": fit.loo_error, "mean": fit.mean,
                       "std": math.sqrt(fit.variance),
                       "first": dict(zip(plan.names, fit.first.tolist())),
                       "total": dict(zip(plan.names, fit.total.tolist()))}
    return out


def tolerance(plan: Plan, rows: list[dict]) -> dict:
    """The widest band of the tolerance's parameter that meets its target (uq.tolerance_band)
    over the complete points."""
    t = plan.study.tolerance
    d = plan.study.parameters[t.parameter].distribution
    ok = [r for r in rows if r["status"] == "complete"]
    answer = uq.tolerance_band([r[t.parameter] for r in ok], [r[t.limit.quantity] for r in ok],
                               0.5 * (d.low + d.high), 0.5 * (d.high - d.low), t.limit.threshold,
                               t.target, t.confidence)
    return {"parameter": t.parameter, "centre": 0.5 * (d.low + d.high), "quantity": t.limit.quantity,
            "threshold": t.limit.threshold, "target": t.target, "confidence": t.confidence,
            "method": "the sampled points inside each narrower band (independent uniform draws "
                      "over it); one-sided Clopper-Pearson upper bound <= target", **answer}
