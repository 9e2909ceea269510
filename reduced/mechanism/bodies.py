"""What a body offers the joints: the interface between the mechanism (reduced.mechanism.
engine: joints, drives, springs, contacts, the equations of motion, written once) and the
kinds of body (reduced.mechanism.planar: rigid bodies in the plane, x, y, phi;
reduced.mechanism.spatial: rigid bodies in space, r and Euler parameters).

A joint sees a body only through the position, velocity and Jacobian of a point and of a
vector fixed in it; a force acts on a body only through `push`. Everything else a body kind
decides for itself: its coordinates and how they move (`body_states`, `state_rates`, the
steps that move a state onto the constraints), its mass (`body_forces`, `fill_schur`) and
its energy. A body kind implements each function below for its own arguments bundle
(its marker, layout.PLANAR or layout.SPATIAL) or for vectors of its dimension (reduced.mechanism.
vectors), with numba.extending.overload; numba picks the implementation when it compiles.

Flexible bodies: a body of a kind may be flexible (its FE modes in a floating frame,
reduced.mechanism.planar), so that one mechanism mixes rigid and flexible bodies; a body's
row in the body states says which it is, and the kind's functions branch on it. A joint
names the body point it acts at, and a vector the point whose frame holds it: on a flexible
body that point's interface frame moves, turns and has its modes' Jacobian columns (`put`
takes the point for them), its mass matrix is full (`fill_schur`, `state_rates`), its
quadratic velocity, elastic and damping forces are `body_forces`'. The joints, drives,
springs and contacts, which call nothing else, work with it unchanged.

Bodies are numbered from 0; -1 is the ground (a point or vector of the ground is global).
Angular quantities are floats in the plane (about its normal) and vectors in space.
"""

import inspect


HOT = {"point_state", "material_velocity", "put", "push", "row_rate"}   # inlined (below)

# The interface a body kind implements: each function, and the argument (its position) whose
# type picks a kind's implementation: "kind" (the arguments' marker) or "vector" (a vector
# of the kind's dimension).
INTERFACE = {
    "body_columns": ("vector", 0), "point_state": ("vector", 2), "vector_state": ("vector", 2),
    "material_velocity": ("vector", 2), "put": ("vector", 4), "push": ("vector", 3),
    "push_torque": ("vector", 3), "centripetal_gap": ("vector", 1),
    "relative_rotation": ("vector", 3), "rotation_axis": ("vector", 2), "row_rate": ("vector", 7),
    "turned": ("vector", 2), "unturned": ("vector", 2),
    "body_states": ("kind", 0), "body_forces": ("kind", 0), "fill_schur": ("kind", 0),
    "state_rates": ("kind", 0), "position_step": ("kind", 0), "velocity_step": ("kind", 0),
    "normalise": ("kind", 0), "kinetic_energy": ("kind", 0)}
OPTIONAL = {"turned", "unturned"}   # a body frame's vectors turned (the spatial state laws')


def implement_kind(namespace: dict, tests: dict) -> None:
    """Register a body kind: each function of INTERFACE that `namespace` (the kind's module)
    defines is the implementation where the argument INTERFACE names passes the kind's test
    (`tests`: "kind", its marker; "vector", a vector of its dimension). A kind without an
    OPTIONAL function leaves it to the kinds that have one."""
    for name, (what, position) in INTERFACE.items():
        if name not in namespace and name in OPTIONAL:
            continue
        implement(globals()[name], namespace[name], tests[what], position)


def implement(declaration, function, applies, position) -> None:
    """Register the compiled `function` as the implementation of the body hook `declaration`
    where `applies(numba type of its argument at position)` (a body kind's marker, or a vector
    of its dimension): numba.extending.overload, the implementation `function` itself (no
    forwarding layer), compiled without the reference-counting runtime like the engine that
    calls it (a body function allocates nothing; numba would count the references of every
    array it receives), its typing function written with `function`'s own parameters (numba
    checks that they match)."""
    from numba.extending import overload   # noqa: PLC0415

    parameters = list(inspect.signature(function.py_func).parameters)
    namespace = {"applies": applies, "implementation": function.py_func}
    exec(f"def typing({', '.join(parameters)}):\n"   # noqa: S102 (names from our own signature)
         f"    if applies({parameters[position]}):\n"
         "        return implementation\n", namespace)
    options = {"inline": "always"} if declaration.__name__ in HOT else {"jit_options": {"_nrt": False}}
    overload(declaration, **options)(namespace["typing"])


def _declared(name, doc):
    def hook(*arguments):
        raise TypeError(f"reduced.mechanism.bodies.{name} runs only inside compiled code, "
                        "implemented by a body kind (reduced.mechanism.planar, .spatial)")
    hook.__name__ = hook.__qualname__ = name
    hook.__doc__ = doc
    return hook


# ---- of a point or a vector fixed in a body (chosen by the vectors' dimension)
point_state = _declared("point_state", """point_state(bodies, b, s): the body point s (body
frame): (its position P, velocity P', the velocity part of its acceleration (P'' less the
part linear in the accelerations: w x (w x s) for a rigid body), the arm s = P - r from the
body's reference point in global axes).""")
vector_state = _declared("vector_state", """vector_state(bodies, b, s, a): the body vector a (body
frame) of the frame at the body point s (a flexible body's interface there; a rigid body's
frame is one): (a in global axes, its rate a', the velocity part of a'').""")
material_velocity = _declared("material_velocity", """material_velocity(bodies, b, x): the
velocity of body b's material point at the global point x.""")
put = _declared("put", """put(jac, row, bodies, b, s, linear, angular, sign, offsets): add sign
times the rate coefficients of the body point s (linear: of the body's translation velocity;
angular: of its angular velocity, the point's arm x linear plus the rotation of a vector of the
frame at s) to body b's columns of a constraint row (a flexible body's: its modes' too).""")
push = _declared("push", """push(force, bodies, b, f, x, offsets): add the generalised forces
of the force f (global) acting at the global point x to body b's columns.""")
push_torque = _declared("push_torque", """push_torque(force, bodies, b, s, torque, offsets): add
a torque (global) on the frame at the body point s to body b's columns.""")
centripetal_gap = _declared("centripetal_gap", """centripetal_gap(bodies, bi, si, bj, sj, a):
a . (c_j - c_i), c the velocity part of the acceleration of the points s_i of body i and s_j
of body j (point_state).""")
relative_rotation = _declared("relative_rotation", """relative_rotation(bodies, bi, bj, s_i,
s_j, a_i, b_j, c_i, offset, drift): the angle of body j's frame at s_j relative to body i's at
s_i about the axis u_i = a_i x c_i (from a_i to b_j), less offset and then less drift (principal value where the body kind
measures angles modulo 2 pi): (angle, the coefficient k of w_i in its rate (-k of w_j), its
rate, the velocity part of its second derivative).""")
row_rate = _declared("row_rate", """row_rate(rate, jac, i, b, states, velocities, offsets, like): rate plus
body b's part of constraint row i's rate (its Jacobian columns times their velocities).""")
rotation_axis = _declared("rotation_axis", """rotation_axis(bodies, bi, s_i, a_i, c_i): the axis
u_i = a_i x c_i of the frame at s_i of a relative rotation in global axes (in the plane: 1.0,
the normal).""")
turned = _declared("turned", """turned(bodies, b, a): a body-frame vector of body b in global
axes (spatial bodies).""")
unturned = _declared("unturned", """unturned(bodies, b, a): a global vector in body b's axes
(spatial bodies).""")

body_columns = _declared("body_columns", """body_columns(like): the width of a body's row in
Work.bodies, the body kind's layout of its kinematic state.""")

# ---- of the whole body (chosen by the type of `kind`, a marker of the body kind without
# data: layout.PLANAR, layout.SPATIAL). Each receives the arrays it may need and no bundle:
# numba counts the references of every array in a bundle a function receives.
body_states = _declared("body_states", """body_states(kind, y, nq, inertia_inv, flex, offsets,
states, velocities): each body's kinematic state from y into its row of `states` (the kind's
layout; flex: a flexible body's modal constants, layout.Args) and its velocity columns into
`velocities`.""")
body_forces = _declared("body_forces", """body_forces(kind, masses, minv, inertia, gravity, flex,
states, force): the forces every body feels of itself into `force`: gravity, the gyroscopic
terms of a spinning body, a flexible body's quadratic velocity terms, elastic and damping
forces; returns the power its modal damping dissipates.""")
fill_schur = _declared("fill_schur", """fill_schur(kind, masses, minv, offsets, states, jac, mjac,
schur, row_bodies, first, m): M^-1 D^T into mjac and the lower triangle of D M^-1 D^T of the
first m constraint rows into schur, within the envelope `first`.""")
state_rates = _declared("state_rates", """state_rates(kind, y, dy, nq, masses, minv, baumgarte,
states, force): dy of the coordinates and their rates from the bodies' velocities and the
generalised forces left in `force` (the constraint forces subtracted).""")
position_step = _declared("position_step", """position_step(kind, y, nq, minv, jac, mjac, x, states,
m): move the coordinates by -M^-1 D^T x (x[:m]; least change in the mass metric).""")
velocity_step = _declared("velocity_step", """velocity_step(kind, y, nq, minv, jac, mjac, x, states,
m, scale): change the velocities by -scale M^-1 D^T x.""")
normalise = _declared("normalise", """normalise(kind, y, nq, offsets): coordinates back onto their own
constraints (unit Euler parameters); nothing for coordinates that have none.""")
kinetic_energy = _declared("kinetic_energy", """kinetic_energy(kind, y, nq, masses, minv, inertia,
flex, offsets): the bodies' kinetic energy (J).""")


# ---- what the joints build of these, for every body kind
import numba  # noqa: E402 (the declarations above are plain Python)

from pinbore.core.compiled import beside, follow_compiled_in  # noqa: E402
from pinbore.reduced.mechanism.vectors import cross, dot  # noqa: E402


@numba.njit(cache=True, _nrt=False)
def dot1(bodies, bi, s_i, a_i, bj, s_j, b_j):
    """a_i . b_j of a vector of body i (its frame at s_i) and one of body j (at s_j)
    ([Nikravesh1988] the dot-1 constraint): (value, coefficient k of w_i (-k: of w_j), rate,
    velocity part of its second derivative)."""
    a, ad, ac = vector_state(bodies, bi, s_i, a_i)
    b, bd, bc = vector_state(bodies, bj, s_j, b_j)
    return dot(a, b), cross(a, b), dot(ad, b) + dot(a, bd), dot(ac, b) + 2 * dot(ad, bd) + dot(a, bc)


# numba's cache follows this file only: the compiled code here also calls into (or reads the
# constants of) these files, and is compiled afresh when they change (core.compiled)
follow_compiled_in(globals(), beside(__file__, "layout", "vectors", "linalg", "planar", "spatial"))
