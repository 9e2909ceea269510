"""Named layouts of the spatial kernel's data (reduced.spatial_kernel): the columns of its row
arrays and the bundles it passes around, in the manner of reduced.layout.

The state vector y holds q (per body: the centre of mass r, 3, then the Euler parameters
p = (e0, e1, e2, e3), 4), q', the two energy integrals of reduced.layout (dissipated, work of
the constraints), then no friction states (the spatial clearance joints take the static
friction laws only). So y has the planar model's layout, with 7 coordinates a body.
"""

from collections import namedtuple

from pinbore.reduced.layout import JOINT_COLUMNS

# ---- primitive constraints (SpatialArgs.primitives): every ideal joint and the drive are
# built of them ([Nikravesh1988] ch. 7: the spherical, dot-1 and dot-2 constraints)
POINT, DOT1, DOT2, ANGLE = 0, 1, 2, 3      # rows: 3, 1, 1, 1
PRIM_KIND, PRIM_BODY_I, PRIM_BODY_J = 0, 1, 2
PRIM_S_I, PRIM_S_J = 3, 6           # points s_i', s_j' (m, body frames; the ground: global)
PRIM_A_I, PRIM_B_J = 9, 12          # unit vectors a_i' (body i), b_j' (body j)
PRIM_C_I = 15                       # ANGLE: the second vector of body i, c_i' = u_i' x a_i'
PRIM_SPEED, PRIM_ANGLE0 = 18, 19    # ANGLE: relative angle = angle0 + speed t (rad/s, rad)
PRIMITIVE_COLUMNS = 20
PRIMITIVE_ROWS = (3, 1, 1, 1)

# ---- clearance joints (SpatialArgs.joints): the planar joint columns that the shared
# friction law reads (reduced.layout: JOINT_CLEARANCE, JOINT_BEARING_RADIUS, JOINT_CHI,
# JOINT_FRICTION_LAW and its parameters), then the spatial geometry
SJ_KIND = JOINT_COLUMNS             # CYLINDER or SPHERE
CYLINDER, SPHERE = 0, 1
SJ_BEARING_BODY, SJ_JOURNAL_BODY = JOINT_COLUMNS + 1, JOINT_COLUMNS + 2
SJ_BEARING_POINT = JOINT_COLUMNS + 3     # bore mid-plane centre or socket centre (3, m)
SJ_BEARING_AXIS = JOINT_COLUMNS + 6      # bore axis (3, unit)
SJ_JOURNAL_POINT = JOINT_COLUMNS + 9     # journal point that sits at the bore centre (3, m)
SJ_JOURNAL_AXIS = JOINT_COLUMNS + 12     # journal axis (3, unit)
SJ_LENGTH = JOINT_COLUMNS + 15           # bore length L (m)
SJ_SLICES = JOINT_COLUMNS + 16           # slices n
SJ_END_LENGTH = JOINT_COLUMNS + 17       # end length e of a sliced law (m)
SJ_SCALE = JOINT_COLUMNS + 18            # stiffness factor a of a sliced law
SJ_AXIAL_CLEARANCE = JOINT_COLUMNS + 19  # m; <= 0: no shoulders
SJ_AXIAL_STIFFNESS = JOINT_COLUMNS + 20  # N/m of the shoulder penalty
SJ_COMPLIANCE = JOINT_COLUMNS + 21       # bulk compliance c_b of a sliced law (m^2/N; 0: none)
SPATIAL_JOINT_COLUMNS = JOINT_COLUMNS + 22
# contact channels: each clearance joint has two (radial or spherical, then axial), each with
# its own onset and impact speed
CHANNELS = 2
RADIAL, AXIAL = 0, 1

# ---- torsion elements (SpatialArgs.torsion): reduced.layout's TORSION_* columns, then the
# relative angle about u_i' from a_i' (body i) to b_j' (body j): ANGLE's construction
TORSION_A_I, TORSION_B_J, TORSION_C_I = 6, 9, 12
SPATIAL_TORSION_COLUMNS = 15

# ---- bundles
# The arguments of the spatial right-hand side and of reduced.integrator.integrate. masses
# (n), inertia and its inverse (n, 3, 3, body frames), gravity (3); speeds: the impact speed
# of each contact channel (2 a clearance joint), latched: a flag per torsion element, mode:
# zeros (no held contacts), all updated in place by the integrator.
SpatialArgs = namedtuple("SpatialArgs", [
    "nq", "masses", "inertia", "inertia_inv", "gravity", "primitives", "baumgarte", "joints",
    "speeds", "grid_log0", "grid_step", "tables", "torsion", "latched", "mode"])

# The buffers of the right-hand side: a row per body (BODY_*: its position, rotation matrix
# and inverse inertia (row-major, global), velocity, angular velocity (global)); the
# constraint rows (Jacobian against (r', omega) of each body, Phi, Phi_t, gamma then the
# multipliers), the Schur matrix (lower triangle), the applied forces and torques (6 a body),
# the normal force of each channel, the rows of M^-1 D^T (6 a body each), the two bodies of
# each constraint row (-1: the ground; a row has nonzero columns for these only) and the
# envelope of the Schur matrix (first coupled row of each row), the last two fixed.
SpatialWork = namedtuple("SpatialWork", [
    "bodies", "jac", "phi", "phi_t", "rhs_c", "schur", "force", "normal", "mjac", "row_bodies",
    "first"])
BODY_POS, BODY_ROT, BODY_VEL, BODY_OMEGA, BODY_JINV = 0, 3, 12, 15, 18
BODY_COLUMNS = 27

# A contact channel's deepest penetration (m) and its approach rate there (m/s).
Depth = namedtuple("Depth", ["delta", "rate"])
