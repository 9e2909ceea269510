# %% [markdown]
# # A pin pushed into its bore, against Persson's closed form
#
# A steel pin of radius 9.99 mm sits in the 10 mm bore of a steel plate: a radial clearance
# c = 10 µm, a thousandth of the radius. A rigid hub at the pin's centre pushes it into the
# bore, step by step, while the plate is held at 20 bore radii. In plane strain every force
# is per unit length of the pin (N/m). Because the clearance is so small, the contact soon
# spreads over a wide arc of the bore: the contact is *conformal*, and Hertz's line contact,
# which assumes an arc small against the radius, no longer holds.
#
# Persson [Persson1964] solved the conformal contact of a pin in the hole of an infinite plate
# of the same material (Ciavarella and Decuzzi [CiavarellaDecuzzi2001] wrote it in closed
# form): the half-angle ε of the contact arc follows from the load P per unit length,
#
#     P / (E* c) = 2π b² (1 + b²) / (2 − ln(1 + b²) − 2 b⁴),    b = tan(ε/2),
#
# with E* the effective modulus of the pair. This demo computes the finite-element curve of
# the push with pinbore, then checks two things it did not use: the contact arc against
# Persson's closed form, and the contact pressure's resultant against the force on the hub.
#
# The method, its equations and what else checks it: [the FE contact](../docs/theory/contact.md).
#
# Set `PINBORE_DEMO_SMALL=1` to run it on fewer load steps (the test suite does), and
# `PINBORE_DEMO_OUT` to choose where its files go (default `build/demos`).

# %%
import json
import math
import os
from pathlib import Path

import numpy as np

import pinbore
from pinbore.fem import curve as curves
from pinbore.laws import elastic

SMALL = os.environ.get("PINBORE_DEMO_SMALL") == "1"
OUT = Path(os.environ.get("PINBORE_DEMO_OUT", "build/demos")) / "push"

# %% [markdown]
# ## The scene
#
# A scene is what `pinbore fem` reads from a TOML file; from Python it may be a dict of the
# same keys. SI units throughout: lengths in m, moduli in Pa. The hub that drives the pin is
# small (0.5 mm), so that the pin's surface deforms as the closed form's free pin does; the
# plate's outer edge, at 20 bore radii, is clamped. The hub moves down (`direction_deg =
# -90`) by up to 26 µm beyond first touch.

# %%
data = {
    "kind": "fem",
    "geometry": {"dim": 2, "pin_radius": 9.99e-3, "bore_radius": 10.0e-3,
                 "housing_radius": 0.2, "hub_radius": 0.5e-3},
    "materials": {"pin": {"E": 210e9, "nu": 0.3}, "bore": {"E": 210e9, "nu": 0.3}},
    "contact": {"method": "penalty", "friction": 0.0},
    "load": {"max_approach": 2.6e-5, "steps": 3 if SMALL else 8, "direction_deg": -90.0},
    "output": {"picture": False},
}

# %% [markdown]
# `pinbore.scene` validates the dict as the command would (a wrong key or value is one
# line naming it) and returns the scene's model, which knows the joint's derived quantities:

# %%
scene = pinbore.scene(data)
joint = scene.joint
print(f"clearance c = {joint.clearance * 1e6:.2f} um, c/R = {joint.clearance / joint.r_bore:.1e}")
print(f"effective modulus E* = {joint.e_star / 1e9:.1f} GPa")
print(f"element size on the expected contact arc: {scene.sizing.contact_size * 1e6:.0f} um "
      f"over +-{math.degrees(scene.sizing.arc_half_angle):.0f} deg")

# %% [markdown]
# ## Mesh, function space, contact, solve
#
# `pinbore.run("fem", ...)` is `pinbore fem` in process. It meshes the pin and the plate with
# Gmsh, fine on the arc where the contact is expected and graded away from it; takes P1
# Lagrange displacements on both bodies (DOLFINx) with linear plane-strain elasticity; lets
# the pin's surface push on the bore through a penalty on the gap (frictionless here); and
# solves each load step by Newton's method. It writes `curve.csv` (one row per converged
# step), `pressure.csv` (the contact state of the arc's nodes) and `result.json` (the model's
# size and the solver's record) to its output folder, and returns the curve.

# %%
curve = pinbore.run("fem", data, out=OUT)
record = json.loads((OUT / "result.json").read_text())
print(f"{record['mesh']['cells']} cells, {record['dofs']} degrees of freedom, "
      f"penalty {record['contact']['penalty_Pa_per_m']:.2e} Pa/m, "
      f"Newton iterations per step {record['newton_iterations']}")

# %% [markdown]
# ## The curve
#
# Force per unit length against the hub's approach beyond first touch, and the contact
# half-angle the FE found at each step (read off the nodes in contact):

# %%
print(" approach (um)   force (kN/m)   half-angle (deg)")
for d, p, eps in zip(curve.approach, curve.force, curve.half_angle):
    print(f"{d * 1e6:14.2f} {p / 1e3:14.1f} {eps:18.2f}")

# %% [markdown]
# ## Check: the contact arc against Persson
#
# The closed form gives the half-angle at each FE force (`persson_half_angles` inverts the
# formula above). The FE and the closed form differ in two ways the comparison allows for: the
# mesh resolves the arc's ends to a fraction of a degree (0.75° allowed; CalculiX comes within
# 0.5–1° on the same problem), and the closed form neglects the clearance against the radius, while the FE pin
# has moved by c, which shifts its points by up to (c/R) sin ε rad.

# %%
closed = np.degrees(elastic.persson_half_angles(curve.force, joint))
tolerance = 0.75 + np.degrees(joint.clearance / joint.r_bore) * np.sin(np.radians(closed))
print(" FE (deg)   Persson (deg)   difference (deg)   allowed (deg)")
for fe, exact, allowed in zip(curve.half_angle, closed, tolerance):
    print(f"{fe:9.2f} {exact:15.2f} {fe - exact:18.2f} {allowed:15.2f}")
assert curve.half_angle.max() > 50, "the push reaches a conformal contact"
assert np.all(np.abs(curve.half_angle - closed) <= tolerance)

# %% [markdown]
# ## Check: the pressure carries the hub's force
#
# Frictionless, the bore pushes back on the pin along the normal only, so the pressure p(θ)
# on the arc (θ measured from the load's direction) must add up to the force on the hub:
#
#     P = ∫ p(θ) cos θ R dθ .
#
# The integral of the nodal pressures by the trapezoidal rule against the hub's force, which
# the FE sums from the elastic forces at the hub's nodes, not from the pressures:

# %%
pressure = curves.read_pressure(OUT / "pressure.csv")
for step, force in zip(curve.step, curve.force):
    at = pressure.step == step
    theta = np.radians(pressure.angle[at])
    order = np.argsort(theta)
    resultant = np.trapezoid((pressure.pressure[at] * np.cos(theta))[order], theta[order]) * joint.r_bore
    print(f"step {step}: integral of the pressure {resultant / 1e3:8.1f} kN/m, "
          f"hub force {force / 1e3:8.1f} kN/m ({resultant / force - 1:+.1e})")
    assert abs(resultant / force - 1) < 5e-3

# %% [markdown]
# Both checks hold: the FE contact opens the arc Persson's closed form predicts, and its
# pressures carry the load. The curve, `curve.csv`, is what the calibration of the contact
# laws reads ([the calibration demo](demo_calibration.py)).
