"""A flexible body of a mechanism, read from the reduced body `pinbore modes` wrote
(pinbore.fem.modes.file, body.npz): what the model needs of it, checked against the scene.
NumPy only (a scene is built without DOLFINx).

The body's frame is Buckens' mean-axis frame of the reduction (origin at the centre of mass,
the mesh's axes); its modes Psi are M-normalised, so its modal mass is the identity. Its
joints act on its interfaces, each tied rigidly to a frame at its centre (RBE2, in the
reduction as here): a point of the body near an interface moves with that frame,

    u(s) = T_k eta + (R_k eta) k x (s - x_k)        (plane: R_k the frame's turn about z),

T_k, R_k the interface's translation and rotation per mode. A point must lie within
INTERFACE_REACH of the body's size from an interface centre: a joint elsewhere would load the
body where the reduction put no interface (its static deformation there is not in the modes).
An output point's elastic displacement is the modes interpolated linearly on the mesh's cell
around it.
"""

from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.fem.modes import file as modes_file

INTERFACE_REACH = 0.1   # of the body's size: how far from an interface centre a joint may act
ON_BODY = 1e-9          # barycentric tolerance of a point on the mesh (its edges and corners)


class Flexible:
    """A planar flexible body: its modes file read and checked, the first n modes kept."""

    def __init__(self, body, base, source: str):
        self.name = body.name
        path = Path(body.modes_file)
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        key = f"{source}: bodies.{body.name}.modes_file"
        if not path.is_file():
            raise InputError(f"{key}: {path} is not a file (pinbore modes writes body.npz)")
        self.path = path
        self.body = reduced = modes_file.read(path)
        if reduced.dim != 2:
            raise InputError(f"{key}: {path} is a {reduced.dim}D body; a planar mechanism needs a "
                             "plane-stress body (dim = 2)")
        n = reduced.modes if body.modes is None else body.modes
        if n > reduced.modes:
            raise InputError(f"{source}: bodies.{body.name}.modes: {n} modes asked, {path} holds "
                             f"{reduced.modes}")
        ratios = np.broadcast_to(np.asarray(body.damping_ratio, float), (n,)) \
            if not isinstance(body.damping_ratio, list) else np.asarray(body.damping_ratio, float)
        if ratios.size != n:
            raise InputError(f"{source}: bodies.{body.name}.damping_ratio: one ratio or one a mode "
                             f"({n} modes), not {ratios.size}")
        self.n, self.ratios, self.stiffening = n, ratios, body.stiffening
        self.mass = float(reduced.mass)
        self.inertia = float(reduced.second_moments[0, 0] + reduced.second_moments[1, 1])
        self.centres = reduced.interface_centres[:, :2]
        self.size = float(np.ptp(reduced.nodes[:, :2], axis=0).max())

    # ---- the engine's constants
    def row(self) -> np.ndarray:
        """The body's row of Args.flex (reduced.mechanism.planar.flex_column)."""
        b, n = self.body, self.n
        omega = b.omega[:n]
        S = b.S[:, :, :n, :n]
        k_g = b.stiffening[2, 2, :n, :n] if self.stiffening else np.zeros((n, n))
        parts = [[n, len(b.interfaces), self.inertia], omega ** 2, 2 * self.ratios * omega,
                 b.s[0, 0, :n] + b.s[1, 1, :n], (S[0, 0] + S[1, 1] - k_g).ravel(),
                 (S[0, 1] - S[1, 0]).ravel()]
        for k in range(len(b.interfaces)):
            parts += [self.centres[k], b.interface_translation[k, 0, :n],
                      b.interface_translation[k, 1, :n], b.interface_rotation[k, 2, :n]]
        return np.concatenate([np.asarray(p, float).ravel() for p in parts])

    def interface_at(self, point, key: str) -> int:
        """The interface a body point acts on (its nearest); one InputError line when it is
        farther than INTERFACE_REACH of the body's size from every interface centre."""
        d = np.hypot(*(self.centres - np.asarray(point, float)[:2]).T)
        k = int(np.argmin(d))
        if d[k] > INTERFACE_REACH * self.size:
            raise InputError(
                f"{key}: {list(point)} on flexible body {self.name!r} is {d[k]:.3g} m from its "
                f"nearest interface {self.body.interfaces[k]!r} at {self.centres[k].round(6).tolist()}: "
                f"a joint acts on a flexible body at an interface (within "
                f"{INTERFACE_REACH * self.size:.3g} m); the modes scene names its interfaces")
        return k

    def shape_at(self, point, key: str) -> np.ndarray:
        """(2, n): the modes' displacement at a body point, interpolated linearly on the mesh
        cell that holds it; one InputError line for a point off the body."""
        nodes, cells = self.body.nodes[:, :2], self.body.cells
        corners = nodes[cells]                                  # (c, 3, 2)
        p = np.asarray(point, float)[:2]
        a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
        v0, v1, v2 = b - a, c - a, p - a
        det = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
        l1 = (v2[:, 0] * v1[:, 1] - v2[:, 1] * v1[:, 0]) / det
        l2 = (v0[:, 0] * v2[:, 1] - v0[:, 1] * v2[:, 0]) / det
        weights = np.stack([1 - l1 - l2, l1, l2], axis=1)
        inside = np.flatnonzero(weights.min(axis=1) >= -ON_BODY)
        if inside.size == 0:
            raise InputError(f"{key}: {list(point)} is not on flexible body {self.name!r} (its "
                             f"mesh spans {nodes.min(0).round(6).tolist()} to "
                             f"{nodes.max(0).round(6).tolist()} in its frame)")
        cell = inside[0]
        psi = self.body.psi[cells[cell], :2, :self.n]             # (3, 2, n)
        return np.einsum("v,vdn->dn", weights[cell], psi)
