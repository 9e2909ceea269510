"""Named layouts of the mechanism's data: the columns of its row arrays, the codes stored in
them, and the bundles passed to the compiled core's engine (pinbore.core.cpp.mechanism,
whose cpp/mechanism/data.h holds the same numbers), for planar and spatial mechanisms alike.

Rows are float arrays (one row per element) addressed by the column names below. A vector in
a row takes three columns, of which a planar mechanism reads two. The bundles are
namedtuples of NumPy arrays, which the core reads in place.

The state vector y of the integrator holds the bodies' coordinates q (a body kind's own: x,
y, phi of a planar body's centre of mass; the centre r and the Euler parameters p of a
spatial one), their rates q', the energy dissipated in the contacts, the work of the
constraint forces, then the friction states of the contacts.
"""

from collections import namedtuple

import numpy as np

# ---- contacts (Model.contacts): one row per contact of a clearance joint. A revolute
# clearance joint of a planar mechanism and a spherical one have one contact (RADIAL); a
# cylindrical one the journal along its bore (SLICED; with rigid impacts: its two ends,
# AXIS_RADIAL) and its shoulders (PLANE, two-sided); a translational one
# its slider's four corners (PLANE, each against the face on its side).
# -- the contact law (the same for every contact of a joint)
CONTACT_CHI = 0             # hysteresis factor chi of the damping law
CONTACT_FRICTION_LAW = 1    # NO_FRICTION ... IWAN
CONTACT_FRICTION = 2        # the law's parameters: FRICTION_PARAMETERS columns, named below
FRICTION_PARAMETERS = 7
CONTACT_STATE = 9           # index in y of the contact's first friction state (-1: none)
CONTACT_IMPACT = 10         # contact model: CONTINUOUS, NEWTON, POISSON
CONTACT_RESTITUTION = 11    # e of the impulse models
CONTACT_REST_SPEED = 12     # m/s: an impulse contact approaching slower is held
# the calibrated damping law (damping_law = "calibrated"): chi against the impact speed v0,
# tabulated at CHI_POINTS speeds equally spaced in ln v0 from CONTACT_CHI_LOG_SPEED by
# CONTACT_CHI_STEP (0: no table, chi is CONTACT_CHI), in CONTACT_CHI_TABLE .. + CHI_POINTS - 1
CONTACT_CHI_LOG_SPEED = 13
CONTACT_CHI_STEP = 14
CONTACT_CHI_TABLE = 15
CHI_POINTS = 33
# -- the geometry
CONTACT_KIND = CONTACT_CHI_TABLE + CHI_POINTS   # RADIAL, SLICED, PLANE
CONTACT_JOINT = CONTACT_KIND + 1     # the clearance joint it belongs to (its index)
CONTACT_TABLE = CONTACT_KIND + 2     # the row of Model.tables with its elastic law
CONTACT_BEARING_BODY = CONTACT_KIND + 3   # body (-1: the ground) of the bearing (bore, guide)
CONTACT_JOURNAL_BODY = CONTACT_KIND + 4   # body of the journal (pin, ball, slider)
CONTACT_BEARING_POINT = CONTACT_KIND + 5  # (3) bore centre, socket centre, guide point (m, body frame)
CONTACT_BEARING_AXIS = CONTACT_KIND + 8   # (3) bore axis (0: none), face normal of a PLANE
CONTACT_JOURNAL_POINT = CONTACT_KIND + 11  # (3) journal centre, ball centre, slider corner
CONTACT_JOURNAL_AXIS = CONTACT_KIND + 14   # (3) SLICED: the journal's axis
CONTACT_CLEARANCE = CONTACT_KIND + 17   # m: c = R_b - R_j (RADIAL, SLICED); a PLANE's offset
CONTACT_RADIUS = CONTACT_KIND + 18      # m: R_b, the contact point's distance from the bore's axis
CONTACT_SIDE = CONTACT_KIND + 19        # PLANE: +1 / -1 one face; 0: both (the nearer)
CONTACT_AT_CONTACT = CONTACT_KIND + 20  # 1: the normal force acts at the contact point on both
#                                        bodies; 0: at the journal point and the bearing point
CONTACT_STIFFNESS = CONTACT_KIND + 21   # N/m: > 0, a linear law (shoulders) instead of the table
CONTACT_FRICTION_ON = CONTACT_KIND + 22  # 1: friction acts (0: a frictionless face)
CONTACT_LENGTH = CONTACT_KIND + 23       # SLICED: bore length L (m)
CONTACT_SLICES = CONTACT_KIND + 24       # SLICED: slices n
CONTACT_END_LENGTH = CONTACT_KIND + 25   # SLICED: end length e of a sliced law (m)
CONTACT_SCALE = CONTACT_KIND + 26        # SLICED: stiffness factor a of a sliced law
CONTACT_COMPLIANCE = CONTACT_KIND + 27   # SLICED: bulk compliance c_b (m^2/N; 0: none)
# a worn journal (a planar RADIAL contact, a spatial SLICED one): its bore's and its pin's
# profile (their row in Args.wear plus one; 0: not worn): its penetration is the mean of order
# WORN_ORDER of the worn surfaces' overlap on the round joint's scale (cpp/mechanism/worn.h)
CONTACT_BORE_WEAR = CONTACT_KIND + 28
CONTACT_PIN_WEAR = CONTACT_KIND + 29
# (3) a worn SLICED contact: the direction normal to the bore's axis (the journal's) in the
# bearing's (journal's) body frame from which its profile's angle runs about the axis
CONTACT_BEARING_REFERENCE = CONTACT_KIND + 30
CONTACT_JOURNAL_REFERENCE = CONTACT_KIND + 33
CONTACT_COLUMNS = CONTACT_KIND + 36
WORN_ORDER = 4   # p of a worn journal's overlap mean, its penetration (cpp/mechanism/worn.h)
RADIAL, SLICED, PLANE, AXIS_RADIAL = 0, 1, 2, 3   # AXIS_RADIAL: a journal point from the bore's axis

# friction laws (column CONTACT_FRICTION_LAW) and their parameter columns
NO_FRICTION, COULOMB, STRIBECK, LINEAR, LUGRE, DAHL, IWAN = 0, 1, 2, 3, 4, 5, 6
COULOMB_MU = CONTACT_FRICTION
STRIBECK_MU_STATIC, STRIBECK_MU_MIN, STRIBECK_V_MIN = (CONTACT_FRICTION, CONTACT_FRICTION + 1,
                                                      CONTACT_FRICTION + 2)
LINEAR_MU_STATIC, LINEAR_ALPHA = CONTACT_FRICTION, CONTACT_FRICTION + 1
REGULARISATION_V0, REGULARISATION_V1 = CONTACT_FRICTION + 5, CONTACT_FRICTION + 6   # the static laws'
LUGRE_MU_COULOMB, LUGRE_MU_STATIC, LUGRE_STRIBECK_SPEED = (CONTACT_FRICTION, CONTACT_FRICTION + 1,
                                                           CONTACT_FRICTION + 2)
LUGRE_SIGMA0, LUGRE_SIGMA1, LUGRE_SIGMA2 = (CONTACT_FRICTION + 3, CONTACT_FRICTION + 4,
                                            CONTACT_FRICTION + 5)
DAHL_MU, DAHL_SIGMA = CONTACT_FRICTION, CONTACT_FRICTION + 1
IWAN_K1, IWAN_K2, IWAN_MU = CONTACT_FRICTION, CONTACT_FRICTION + 1, CONTACT_FRICTION + 2
# friction states of a contact point: LuGre and Dahl one, Iwan two (travel, Jenkins stretch),
# each of as many components as the contact has tangent directions (1 in the plane, 3 in
# space: a vector in the bearing body's frame, of which the tangent part acts)
STATE_TRAVEL, STATE_STRETCH = 0, 1

# contact models (column CONTACT_IMPACT)
CONTINUOUS, NEWTON, POISSON = 0, 1, 2

# ---- primitive constraints (Model.primitives): every ideal joint and the drive are built of
# them ([Nikravesh1988] ch. 7: the spherical, dot-1 and dot-2 constraints, and an angle)
POINT, DOT1, DOT2, ANGLE = 0, 1, 2, 3      # rows: D (2 or 3), 1, 1, 1
PRIM_KIND, PRIM_BODY_I, PRIM_BODY_J = 0, 1, 2
PRIM_S_I, PRIM_S_J = 3, 6           # points s_i', s_j' (m, body frames; the ground: global);
#                                     of an ANGLE or DOT1, the point whose frame holds its vectors
PRIM_A_I, PRIM_B_J = 9, 12          # unit vectors a_i' (body i), b_j' (body j)
PRIM_C_I = 15                       # ANGLE: the second vector of body i, c_i' = u_i' x a_i'
PRIM_SPEED, PRIM_ANGLE0 = 18, 19    # ANGLE: relative angle = angle0 + theta(t) (rad/s, rad)
PRIM_PROFILE = 20                   # ANGLE: theta(t) = speed t (CONSTANT_SPEED), the smooth
PRIM_PROFILE_TIME = 21              # spin-up to `speed` over PRIM_PROFILE_TIME (s) (SPIN_UP),
PRIM_PROFILE_ROWS = 22              # or the PRIM_PROFILE_ROWS segments of Args.profile from
PRIMITIVE_COLUMNS = 23              # row PRIM_PROFILE_TIME (TABLE), or the sum of the harmonics
CONSTANT_SPEED, SPIN_UP, TABLE, HARMONIC = 0, 1, 2, 3   # in those rows (HARMONIC)
# a drive table's segments (Args.profile, a row each): from time SEG_TIME, theta = c0 + c1 tau
# + c2 tau^2 + c3 tau^3 (rad), tau = t - SEG_TIME; the last segment runs on without end
SEG_TIME, SEG_C0, SEG_C1, SEG_C2, SEG_C3 = 0, 1, 2, 3, 4
PROFILE_COLUMNS = 5
# a harmonic drive's harmonics (Args.profile, a row each): theta = sum A (sin(w t + phi) - sin phi)
HARM_AMPLITUDE, HARM_OMEGA, HARM_PHASE = 0, 1, 2   # rad, rad/s, rad

# ---- torsion spring, stop or latch (Model.torsion): a torque about body i's axis u_i' on
# the relative angle from a_i' (body i) to b_j' (body j), measured like the ANGLE primitive
TORSION_BODY_I, TORSION_BODY_J = 0, 1
TORSION_STIFFNESS, TORSION_DAMPING = 2, 3    # N m/rad, N m s/rad
TORSION_FREE_ANGLE = 4                       # rad, relative to the bodies' initial relative angle
TORSION_KIND = 5                             # SPRING, STOP, LATCH
TORSION_A_I, TORSION_B_J, TORSION_C_I = 6, 9, 12
TORSION_S_I, TORSION_S_J = 15, 18   # the points (body frames) whose frames the element joins:
TORSION_COLUMNS = 21                # a flexible body's interface there (rigid bodies: unused)
SPRING, STOP, LATCH = 0, 1, 2

# ---- linear spring-dampers between two points (Model.springs): a tension T = k (L - L0) + c L'
# pulls point s_i of body i and point s_j of body j together along the line between them
SPRING_BODY_I, SPRING_BODY_J = 0, 1
SPRING_S_I, SPRING_S_J = 2, 5                                # (3) body frames; the ground: global
SPRING_STIFFNESS, SPRING_DAMPING, SPRING_LENGTH = 8, 9, 10   # N/m, N s/m, m (free length L0)
SPRING_COLUMNS = 11

# ---- harmonic loads (Model.loads): a force F cos(w t + phi) at a body point and a torque
# T cos(w t + phi) on the body's frame there, both amplitudes global
LOAD_BODY = 0
LOAD_POINT = 1      # (3) m, body frame
LOAD_FORCE = 4      # (3) N
LOAD_TORQUE = 7     # (3) N m (a planar mechanism reads the third, about the plane's normal)
LOAD_OMEGA, LOAD_PHASE = 10, 11   # rad/s, rad
LOAD_COLUMNS = 12

# ---- the state vector after q and q': the energy integrals, then the friction states
DISSIPATED, WORK_IN = 0, 1
ENERGY_STATES = 2

# ---- impact log of the integrator: one row per impact or contact onset
LOG_TIME, LOG_JOINT, LOG_RATE, LOG_IMPULSE = 0, 1, 2, 3   # s, joint, approach rate m/s, N s
LOG_COLUMNS = 4

# ---- bundles
# The arguments of the right-hand side and of the integrator (reduced.mechanism.model.Model.
# args), one set of fields for every body kind: `like` a zero vector of the mechanism's
# dimension, on whose length the core chooses the body kind (planar, spatial), `project_first`
# whether an accepted step is projected onto the constraints before its events are read
# (spatial) or after (planar): each kind keeps the order it has always had, so that a run
# gives the numbers it gave before to the last bit (in a chaotic mechanism a rounding apart
# grows to another trajectory); both read the events within the onset tolerance of the
# constraints. masses (per body), minv (per velocity column: planar 1/m, 1/m, 1/J), inertia
# and its inverse (per body, 3 x 3 in the body frame; planar: J in [0, 0]), gravity (D,
# m/s^2), offsets (per body its first velocity column; the last entry their number),
# profile: the drive table's segments (SEG_*; none: an empty array), flex: per body the
# constants of a flexible body's modes (the body kind's layout; a rigid body's row is zero),
# springs and loads: the spring-dampers' and the harmonic loads' rows (SPRING_*, LOAD_*);
# wear: the worn profiles of journals and bores, a row each, the depth (m) at angles of its
# body's frame evenly spaced from -pi (none: an empty array).
# speeds: impact speed per contact; latched: a flag per torsion element; mode: per contact 1
# while an impulse contact is held; all updated in place by the integrator.
Args = namedtuple("Args", [
    "nq", "like", "project_first", "masses", "minv", "inertia", "inertia_inv", "gravity",
    "offsets", "primitives", "baumgarte", "contacts", "speeds", "grid_log0", "grid_step", "tables",
    "torsion", "latched", "mode", "profile", "flex", "springs", "loads", "wear"],
    defaults=[np.zeros((0, 1))])

# The buffers of the right-hand side: a row per body of its kinematic state (the body kind's
# layout), the velocity of every Jacobian column, the constraint rows (Jacobian against the
# bodies' velocities, Phi, Phi_t, gamma then the multipliers), the Schur matrix (lower
# triangle), the applied forces (a column each), the normal and friction forces of each
# contact, the rows of M^-1 D^T, the two bodies of each constraint row (-1: the ground or none; ascending) and the
# envelope of the Schur matrix (first coupled row of each row).
Work = namedtuple("Work", ["bodies", "velocities", "jac", "phi", "phi_t", "rhs_c", "schur",
                           "force", "normal", "friction", "mjac", "row_bodies", "first"])

# The integrator's status codes (cpp/mechanism/data.h; its STOPPED never reaches Python: the
# binding raises the stop's exception) and methods (cpp/mechanism/integrator.h).
OK, BLOWN_UP, TOO_MANY_STEPS, STEP_TOO_SMALL = 0, 1, 2, 3
DOPRI5, DOPRI5_FIXED, ROSENBROCK23 = 0, 1, 2

# What the integrator returns: the record cut to the accepted steps, the impact log,
# counters (accepted, rejected, rhs calls, impacts), status code, time reached.
Integration = namedtuple("Integration", [
    "times", "states", "speeds", "modes", "latched", "impacts", "counters", "status", "t_end"])


def row(columns: int, values: dict) -> list:
    """A row of `columns` floats, zero but for `values` ({column: value}; a tuple or list
    value fills the columns from there)."""
    out = [0.0] * columns
    for column, value in values.items():
        if isinstance(value, (tuple, list)):
            out[column:column + len(value)] = [float(v) for v in value]
        else:
            out[column] = value
    return out
