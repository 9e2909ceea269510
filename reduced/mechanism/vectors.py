"""Small vectors as tuples, written once for the plane and for space.

A mechanism's geometry is written against these functions whatever its dimension: a vector
is a tuple of two floats (a planar mechanism) or of three (a spatial one), and an angular
quantity (an angular velocity, the moment arm of a force) is a float in the plane (its
component along the plane's normal) and a vector in space. numba compiles each function for
the tuples it is given (numba.extending.overload on the tuple's length), so the dimension is
settled when the code compiles and costs nothing when it runs; tuples allocate nothing.

Each function is also plain Python on tuples, so that post-processing may call it. The
arithmetic is the one the planar and the spatial models have always done, operation by
operation (a planar unit normal is e / |e| with |e| = hypot, a spatial one e (1 / |e|)):
a mechanism run with this code gives the numbers it gave before, to the last bit.
"""

import math

from numba import types
from numba.extending import overload


def _plane(t) -> bool:
    return isinstance(t, types.UniTuple) and t.count == 2


def _space(t) -> bool:
    return isinstance(t, types.UniTuple) and t.count == 3


def _scalar(t) -> bool:
    return isinstance(t, (types.Float, types.Integer))


# ---- reading vectors out of a row of floats
def vec(a, i, like):
    """The vector of `like`'s dimension stored in a[i], a[i + 1] (, a[i + 2])."""
    return tuple(float(a[i + k]) for k in range(len(like)))


@overload(vec)
def _vec(a, i, like):
    if _plane(like):
        return lambda a, i, like: (a[i], a[i + 1])
    if _space(like):
        return lambda a, i, like: (a[i], a[i + 1], a[i + 2])


def zero(like):
    """The zero vector of `like`'s dimension."""
    return tuple(0.0 for _ in like)


@overload(zero)
def _zero(like):
    if _plane(like):
        return lambda like: (0.0, 0.0)
    if _space(like):
        return lambda like: (0.0, 0.0, 0.0)


def axis(c, like):
    """The unit vector of the c-th global axis, in `like`'s dimension."""
    return tuple(1.0 if k == c else 0.0 for k in range(len(like)))


@overload(axis)
def _axis(c, like):
    if _plane(like):
        return lambda c, like: (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0)
    if _space(like):
        return lambda c, like: (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0,
                                1.0 if c == 2 else 0.0)


def angular_zero(like):
    """A zero angular quantity of `like`'s dimension: 0.0 in the plane, a zero vector in space."""
    return 0.0 if len(like) == 2 else (0.0, 0.0, 0.0)


@overload(angular_zero)
def _angular_zero(like):
    if _plane(like):
        return lambda like: 0.0
    if _space(like):
        return lambda like: (0.0, 0.0, 0.0)


# ---- algebra
def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


@overload(add)
def _add(a, b):
    if _plane(a):
        return lambda a, b: (a[0] + b[0], a[1] + b[1])
    if _space(a):
        return lambda a, b: (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


@overload(sub)
def _sub(a, b):
    if _plane(a):
        return lambda a, b: (a[0] - b[0], a[1] - b[1])
    if _space(a):
        return lambda a, b: (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scaled(a, k):
    """k a (a vector, or an angular quantity)."""
    return k * a if not isinstance(a, tuple) else tuple(k * x for x in a)


@overload(scaled)
def _scaled(a, k):
    if _scalar(a):
        return lambda a, k: k * a
    if _plane(a):
        return lambda a, k: (k * a[0], k * a[1])
    if _space(a):
        return lambda a, k: (k * a[0], k * a[1], k * a[2])


def negated(a):
    return -a if not isinstance(a, tuple) else tuple(-x for x in a)


@overload(negated)
def _negated(a):
    if _scalar(a):
        return lambda a: -a
    if _plane(a):
        return lambda a: (-a[0], -a[1])
    if _space(a):
        return lambda a: (-a[0], -a[1], -a[2])


def dot(a, b):
    """a . b (of two vectors, or of two angular quantities)."""
    if not isinstance(a, tuple):
        return a * b
    out = a[0] * b[0]
    for x, y in zip(a[1:], b[1:]):
        out += x * y
    return out


@overload(dot)
def _dot(a, b):
    if _scalar(a):
        return lambda a, b: a * b
    if _plane(a):
        return lambda a, b: a[0] * b[0] + a[1] * b[1]
    if _space(a):
        return lambda a, b: a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    """a x b. In the plane: two vectors give the normal component (a float); an angular
    quantity (a float, about the normal) and a vector give the vector w x b, a vector and a
    float the vector a x w."""
    if not isinstance(a, tuple):
        return (-a * b[1], a * b[0])
    if not isinstance(b, tuple):
        return (a[1] * b, -a[0] * b)
    if len(a) == 2:
        return a[0] * b[1] - a[1] * b[0]
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@overload(cross)
def _cross(a, b):
    if _scalar(a) and _plane(b):
        return lambda a, b: (-a * b[1], a * b[0])
    if _plane(a) and _scalar(b):
        return lambda a, b: (a[1] * b, -a[0] * b)
    if _plane(a) and _plane(b):
        return lambda a, b: a[0] * b[1] - a[1] * b[0]
    if _space(a) and _space(b):
        return lambda a, b: (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                             a[0] * b[1] - a[1] * b[0])


def norm(a):
    """|a|: math.hypot in the plane, the root of a . a in space."""
    return math.hypot(*a) if len(a) == 2 else math.sqrt(dot(a, a))


@overload(norm)
def _norm(a):
    if _plane(a):
        return lambda a: math.hypot(a[0], a[1])
    if _space(a):
        return lambda a: math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def direction(a, size):
    """a / |a| given size = |a| > 0: each component divided in the plane, scaled by 1 / |a|
    in space."""
    return tuple(x / size for x in a) if len(a) == 2 else tuple(x * (1.0 / size) for x in a)


@overload(direction)
def _direction(a, size):
    if _plane(a):
        return lambda a, size: (a[0] / size, a[1] / size)
    if _space(a):
        return lambda a, size: scaled(a, 1.0 / size)


def tangent(n):
    """In the plane, the unit tangent (-n_y, n_x) of a unit normal n (a quarter turn)."""
    return (-n[1], n[0])


@overload(tangent)
def _tangent(n):
    if _plane(n):
        return lambda n: (-n[1], n[0])


def perpendicular(u):
    """A unit vector normal to the unit vector u (in space: across the axis of u's smallest
    component; in the plane: a quarter turn)."""
    if len(u) == 2:
        return (-u[1], u[0])
    a0, a1, a2 = abs(u[0]), abs(u[1]), abs(u[2])
    helper = (1.0, 0.0, 0.0) if a0 <= a1 and a0 <= a2 else ((0.0, 1.0, 0.0) if a1 <= a2 else (0.0, 0.0, 1.0))
    f = cross(u, helper)
    return scaled(f, 1.0 / math.sqrt(dot(f, f)))


@overload(perpendicular)
def _perpendicular(u):
    if _plane(u):
        return lambda u: (-u[1], u[0])
    if _space(u):
        def impl(u):
            a0, a1, a2 = abs(u[0]), abs(u[1]), abs(u[2])
            helper = (1.0, 0.0, 0.0) if a0 <= a1 and a0 <= a2 else \
                ((0.0, 1.0, 0.0) if a1 <= a2 else (0.0, 0.0, 1.0))
            f = cross(u, helper)
            return scaled(f, 1.0 / math.sqrt(dot(f, f)))
        return impl


def cell(a, r, i, like):
    """The vector of `like`'s dimension stored in row r of a 2D array from column i (read in
    place: a row view would have its references counted)."""
    return tuple(float(a[r, i + k]) for k in range(len(like)))


@overload(cell)
def _cell(a, r, i, like):
    if _plane(like):
        return lambda a, r, i, like: (a[r, i], a[r, i + 1])
    if _space(like):
        return lambda a, r, i, like: (a[r, i], a[r, i + 1], a[r, i + 2])


def angular_cell(a, r, i, k, like):
    """k times the angular quantity stored in row r of a 2D array from column i, as a vector
    of three: in the plane its third component (about the plane's normal), a float; in space
    the vector."""
    if len(like) == 2:
        return k * float(a[r, i + 2])
    return tuple(k * float(a[r, i + c]) for c in range(3))


@overload(angular_cell)
def _angular_cell(a, r, i, k, like):
    if _plane(like):
        return lambda a, r, i, k, like: k * a[r, i + 2]
    if _space(like):
        return lambda a, r, i, k, like: (k * a[r, i], k * a[r, i + 1], k * a[r, i + 2])
