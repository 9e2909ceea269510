r"""Fitting contact laws to FE curves.

Published form: the law with parameters from geometry and materials only; its error is the
relative error of the force per length over the FE approaches.

Fitted form: the law's own dependence on geometry, materials and approach, corrected by a
stiffness factor s and an exponent correction q about a reference approach d_ref (the
geometric mean of the approaches):

    P_fit(d) = s P_law(d) (d / d_ref)^q .

For a power law K d^n this fits K and n. In logarithms the model is linear,
ln(P_FE / P_law) = ln s + q ln(d / d_ref), so the fit is ordinary least squares on the
relative error, in closed form, with 95 % confidence intervals from Student's t. The linear
spring has no published stiffness: it is fitted as P = s E* d (s alone). The fitted law is a
`Fit` of laws.json (laws/lawsfile.py); its force is `Fit.force`.
"""

import numpy as np
from scipy import stats

from pinbore.laws.lawsfile import EXPONENT_CORRECTION, MODEL, Errors, Fit, law_force


def errors(predicted, measured) -> Errors:
    ok = np.isfinite(predicted)
    rel = predicted[ok] / measured[ok] - 1
    if not ok.any():
        return Errors(max_rel=float("inf"), rms_rel=float("inf"), points=0)
    return Errors(max_rel=float(np.max(np.abs(rel))), rms_rel=float(np.sqrt(np.mean(rel**2))),
                  points=int(ok.sum()))


class NotFitted(Exception):
    """The law has too few approaches with a solution to fix its parameters."""


def fit(name: str, curves) -> Fit:
    """s and q of law `name` over all points of `curves` where the law has a solution."""
    d = np.concatenate([c.approach for c in curves])
    ratio = np.concatenate([c.force / law_force(name, c.approach, c.joint) for c in curves])
    ok = np.isfinite(ratio) & (ratio > 0)
    d, y = d[ok], np.log(ratio[ok])
    reference = float(np.exp(np.mean(np.log(d))))
    x = np.log(d / reference)
    with_exponent = name != "linear"
    design = np.column_stack([np.ones_like(x), x]) if with_exponent else np.ones((x.size, 1))
    dof = x.size - design.shape[1]
    if dof < 1:
        raise NotFitted(f"{name}: {x.size} approaches inside its range cannot fix "
                        f"{design.shape[1]} parameters")
    coef, residual, *_ = np.linalg.lstsq(design, y, rcond=None)
    sigma2 = float(np.sum((y - design @ coef) ** 2)) / dof
    half = stats.t.ppf(0.975, dof) * np.sqrt(np.diag(sigma2 * np.linalg.inv(design.T @ design)))
    q, q_half = (float(coef[1]), float(half[1])) if with_exponent else (0.0, 0.0)
    if not (np.all(np.isfinite(coef)) and np.isfinite(np.exp(coef[0])) and abs(q) <= EXPONENT_CORRECTION):
        raise NotFitted(f"{name}: the fit's scale {np.exp(coef[0]):.3g} or exponent correction "
                        f"{q:.3g} is beyond a contact law's (|q| <= {EXPONENT_CORRECTION:g})")
    return Fit(model=MODEL, scale=float(np.exp(coef[0])),
               scale_ci95=[float(np.exp(coef[0] - half[0])), float(np.exp(coef[0] + half[0]))],
               exponent_correction=q, exponent_correction_ci95=[q - q_half, q + q_half],
               reference_approach_m=reference, points=int(x.size))
