"""The quality verdict of a reduced run: is what it computed physical?

An integrator that reaches the end time has not yet earned `complete`. A run whose tolerance
is too loose for its contact stiffness, or a law driven outside its range, ends normally and
prints plausible numbers. The summary already holds what exposes it, and a run that breaks any
of these rules is `suspect`, with the reasons:

- energy balance: kinetic + potential + elastic + dissipated - drive work must stay constant;
  a residual above ENERGY_RESIDUAL of the peak kinetic energy means the integration (or a
  law) created or lost energy that is not booked;
- dissipation: the damping and friction laws only take energy out; a total below minus the
  energy residual is not round-off;
- penetration: a clearance joint's penetration beyond PENETRATION times its clearance leaves
  every contact law of the library (they assume an approach small against the clearance, or,
  conformal, of its order) and, for a stiff law, means missed or tunnelled contact;
- friction: the peak friction force over the peak normal force is a lower bound of the largest
  ratio F_t / F_n during the run; above the law's largest coefficient (with FRICTION_MARGIN)
  the law's bound was broken (laws without a bound in F_t / F_n, the linear velocity law,
  LuGre with its damping terms, Iwan with a parallel spring, are not checked here);
- constraint drift: the ideal joints' largest gap above DRIFT of the smallest clearance (or of
  a millimetre without clearance joints).
"""

import math

from pinbore.reduced.mechanism.scene import clearance_joints

ENERGY_RESIDUAL = 1e-2     # of the peak kinetic energy
PENETRATION = 1.0          # of the joint's clearance
FRICTION_MARGIN = 1.05     # over the law's largest coefficient
DRIFT = 1e-3               # of the smallest clearance (of 1 mm without clearance joints)


def friction_bound(friction) -> float:
    """The largest |F_t| / F_n that a friction table allows (inf: the law sets no bound)."""
    if friction is None:
        return 0.0
    law = friction.law
    if law == "coulomb_ambrosio":
        return friction.mu
    if law == "stribeck":
        return max(friction.mu_static, friction.mu_min)
    if law == "dahl":
        return friction.mu
    if law == "iwan_bilinear" and friction.k2 == 0:
        return friction.mu
    return math.inf


def reasons(summary, scene) -> list[str]:
    """What makes the run suspect, one phrase each (empty: nothing)."""
    found = []
    energy = summary.energy_balance
    if not energy.relative_to_peak_kinetic <= ENERGY_RESIDUAL:   # NaN fails too
        remedy = ("shorten integrator.fixed_step" if scene.integrator.method == "dopri5_fixed"
                  else "tighten integrator.rtol")
        found.append(f"energy residual {energy.relative_to_peak_kinetic:.3g} of the peak kinetic "
                     f"energy (above {ENERGY_RESIDUAL:g}): {remedy}")
    if energy.dissipated_J < -max(energy.max_residual_J, 1e-12):
        found.append(f"negative dissipated energy {energy.dissipated_J:.3g} J")
    for joint in clearance_joints(scene):
        peaks = summary.clearance_joints.get(joint.name)
        if peaks is None:
            continue
        if not peaks.peak_penetration_m <= PENETRATION * peaks.clearance_m:
            found.append(f"{joint.name}: penetration {peaks.peak_penetration_m / peaks.clearance_m:.3g} "
                         f"times the clearance (above {PENETRATION:g})")
        bound = friction_bound(joint.friction)
        if peaks.peak_normal_force_N > 0 and math.isfinite(bound):
            ratio = peaks.peak_friction_force_N / peaks.peak_normal_force_N
            if ratio > FRICTION_MARGIN * bound:
                found.append(f"{joint.name}: friction force {ratio:.3g} times the normal force, "
                             f"above the law's largest coefficient {bound:g}")
    clearances = [peaks.clearance_m for peaks in summary.clearance_joints.values()]
    drift_limit = DRIFT * (min(clearances) if clearances else 1e-3)
    if not summary.constraint_drift_max <= drift_limit:
        found.append(f"constraint drift {summary.constraint_drift_max:.3g} m (above {drift_limit:.3g} m)")
    return found
