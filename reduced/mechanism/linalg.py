"""The small dense linear algebra of the constraint solve: the Schur matrix D M^-1 D^T within
its envelope and its Cholesky factorisation, for every body kind.

A constraint row has nonzero Jacobian columns for its two bodies only (Work.row_bodies), and
two rows couple only through a body they share: the envelope of the Schur matrix (first[i],
the first row k <= i that shares a body with row i) leaves out the blocks of bodies that
share no joint (in the slider-crank, the slider's rows and the crank's), and the
factorisation keeps it. Entries outside the envelope are exact zeros, so the result is the
dense one to the last bit.
"""

import math

import numba


@numba.njit(cache=True, _nrt=False)
def cholesky_solve(a, b, m, first=None):
    """Solve a x = b in place (x in b) for the leading m x m block of a small symmetric
    positive semi-definite a (its lower triangle; overwritten). A row that depends on the
    rows before it (a pivot below 1e-10 of its diagonal: redundant constraints, as a closed
    loop of revolute joints in space has) is dropped, its unknown set to 0: for consistent
    equations the others still solve them all. `first` (optional): the envelope of a, first[i]
    the column of row i's first nonzero in its lower triangle (a's entries left of it are not
    read); the factor keeps that envelope (fill-in stays inside it), so the sums start there."""
    for j in range(m):
        fj = envelope(first, j)
        d = a[j, j]
        scale = d
        for k in range(fj, j):
            d -= a[j, k] * a[j, k]
        if d <= 1e-10 * scale:
            a[j, j] = 0.0
            for i in range(j + 1, m):
                a[i, j] = 0.0
            continue
        a[j, j] = math.sqrt(d)
        for i in range(j + 1, m):
            fi = envelope(first, i)
            if fi > j:
                continue
            v = a[i, j]
            for k in range(max(fi, fj), j):
                v -= a[i, k] * a[j, k]
            a[i, j] = v / a[j, j]
    for i in range(m):
        v = b[i]
        for k in range(envelope(first, i), i):
            v -= a[i, k] * b[k]
        b[i] = v / a[i, i] if a[i, i] > 0.0 else 0.0
    for i in range(m - 1, -1, -1):
        v = b[i]
        for k in range(i + 1, m):
            if envelope(first, k) <= i:
                v -= a[k, i] * b[k]
        b[i] = v / a[i, i] if a[i, i] > 0.0 else 0.0


@numba.njit(cache=True, _nrt=False)
def envelope(first, i):
    """The first column of row i's envelope (cholesky_solve): 0 without an envelope."""
    if first is None:
        return 0
    return first[i]


@numba.njit(cache=True, _nrt=False)
def shares_body(row_bodies, i, k):
    """Whether constraint rows i and k act on a common (moving) body."""
    for side in range(2):
        b = row_bodies[i, side]
        if b >= 0 and (b == row_bodies[k, 0] or b == row_bodies[k, 1]):
            return True
    return False


@numba.njit(cache=True, _nrt=False)
def envelope_of(row_bodies, first, start, m):
    """first[i] for the rows start..m-1: the first row k <= i that shares a body with row i."""
    for i in range(start, m):
        first[i] = i
        for k in range(i):
            if shares_body(row_bodies, i, k):
                first[i] = k
                break


@numba.njit(cache=True, _nrt=False)
def schur_within_envelope(jac, mjac, schur, row_bodies, first, offsets, m, mass_left):
    """The lower triangle of D M^-1 D^T (D: jac, M^-1 D^T: the rows of mjac) of the first m
    rows within the envelope: entry (i, k) sums over the columns of the bodies the two rows
    share, in ascending order, mjac_i jac_k (mass_left) or jac_i mjac_k (the same number but
    for rounding: a body kind keeps the order it has always used)."""
    for i in range(m):
        for k in range(first[i], i + 1):
            v = 0.0
            for side in range(2):
                b = row_bodies[i, side]
                if b >= 0 and (b == row_bodies[k, 0] or b == row_bodies[k, 1]):
                    if mass_left:
                        for c in range(offsets[b], offsets[b + 1]):
                            v += mjac[i, c] * jac[k, c]
                    else:
                        for c in range(offsets[b], offsets[b + 1]):
                            v += jac[i, c] * mjac[k, c]
            schur[i, k] = v
