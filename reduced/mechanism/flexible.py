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

import json
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.fem.modes import file as modes_file

FLEXIBLE_KEYS = ("modes_file", "modes", "damping_ratio", "stiffening")
INTERFACE_REACH = 0.1   # of the body's size: how far from an interface centre a joint may act
ON_BODY = 1e-9          # barycentric tolerance of a point on the mesh (its edges and corners)


class Flexible:
    """A flexible body of a mechanism of dimension `dim`: its modes file read and checked, the
    first n modes kept."""

    def __init__(self, body, base, source: str, dim: int):
        self.name = body.name
        path = Path(body.modes_file)
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        key = f"{source}: bodies.{body.name}.modes_file"
        if not path.is_file():
            raise InputError(f"{key}: {path} is not a file (pinbore modes writes body.npz)")
        self.path = path
        self.body = reduced = modes_file.read(path)
        if reduced.dim != dim:
            raise InputError(f"{key}: {path} is a {reduced.dim}D body; a "
                             f"{'planar' if dim == 2 else 'spatial'} mechanism needs a "
                             f"{'plane-stress (dim = 2)' if dim == 2 else 'solid (dim = 3)'} body")
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
        self.dim = dim
        self.mass = float(reduced.mass)
        self.inertia = reduced.inertia if dim == 3 else float(reduced.inertia[2, 2])
        self.centres = reduced.interface_centres[:, :dim]
        self.size = float(np.ptp(reduced.nodes[:, :dim], axis=0).max())

    @property
    def stiffening_matrices(self) -> np.ndarray:
        """K_G,ab of the kept modes (3, 3, n, n); zero without the stiffening."""
        k_g = self.body.stiffening[:, :, :self.n, :self.n]
        return k_g if self.stiffening else np.zeros_like(k_g)

    def interface_at(self, point, key: str) -> int:
        """The interface a body point acts on (its nearest); one InputError line when it is
        farther than INTERFACE_REACH of the body's size from every interface centre."""
        d = np.linalg.norm(self.centres - np.asarray(point, float)[:self.dim], axis=1)
        k = int(np.argmin(d))
        if d[k] > INTERFACE_REACH * self.size:
            raise InputError(
                f"{key}: {list(point)} on flexible body {self.name!r} is {d[k]:.3g} m from its "
                f"nearest interface {self.body.interfaces[k]!r} at {self.centres[k].round(6).tolist()}: "
                f"a joint acts on a flexible body at an interface (within "
                f"{INTERFACE_REACH * self.size:.3g} m); the modes scene names its interfaces")
        return k

    def shape_at(self, point, key: str) -> np.ndarray:
        """(dim, n): the modes' displacement at a body point, interpolated linearly on the mesh
        cell (triangle, tetrahedron) that holds it; one InputError line for a point off the
        body."""
        dim = self.dim
        nodes, cells = self.body.nodes[:, :dim], self.body.cells
        corners = nodes[cells]                                   # (c, dim + 1, dim)
        p = np.asarray(point, float)[:dim]
        edges = np.transpose(corners[:, 1:] - corners[:, :1], (0, 2, 1))   # (c, dim, dim)
        det = np.linalg.det(edges)
        good = np.abs(det) > 0
        local = np.zeros((cells.shape[0], dim))
        local[good] = np.linalg.solve(edges[good], (p - corners[good, 0])[..., None])[..., 0]
        weights = np.concatenate([1 - local.sum(axis=1, keepdims=True), local], axis=1)
        inside = np.flatnonzero(good & (weights.min(axis=1) >= -ON_BODY))
        if inside.size == 0:
            raise InputError(f"{key}: {list(point)} is not on flexible body {self.name!r} (its "
                             f"mesh spans {nodes.min(0).round(6).tolist()} to "
                             f"{nodes.max(0).round(6).tolist()} in its frame)")
        cell = inside[0]
        psi = self.body.psi[cells[cell], :dim, :self.n]           # (dim + 1, dim, n)
        return np.einsum("v,vdn->dn", weights[cell], psi)


class FlexibleGeometry:
    """What a body kind's Geometry (reduced.mechanism.planar, .spatial) knows of its flexible
    bodies, written once: a kind sets DIM, RIGID_COLUMNS and RIGID_COORDINATES (a rigid body's
    velocity columns and coordinates: a flexible body's modes follow them), MODES and
    INTERFACES (the most its rows hold), and defines `attachments()` (the points its joints fix
    on bodies), `coordinate(b)` and `constants(flexible)` (a body's row of Args.flex)."""

    DIM = RIGID_COLUMNS = RIGID_COORDINATES = MODES = INTERFACES = 0

    def read_flexible(self, scene, index, source: str, base) -> None:
        """The flexible bodies read and checked (their modes and interfaces within the rows,
        every point on a body at an interface, every output point on its body), each body's
        first velocity column (`columns`) and the output points with their mode shapes."""
        self.flexible = {b.name: Flexible(b, base, source, self.DIM) for b in scene.bodies if b.flexible}
        for name, f in self.flexible.items():
            if f.n > self.MODES or len(f.centres) > self.INTERFACES:
                raise InputError(f"{source}: bodies.{name}.modes_file: at most {self.MODES} modes "
                                 f"and {self.INTERFACES} interfaces a flexible body")
        counts = [self.RIGID_COLUMNS + self.modes(b.name) for b in scene.bodies]
        self.columns = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        attached = [(e.body_i, e.point_i, "springs.point_i") for e in scene.springs]
        attached += [(e.body_j, e.point_j, "springs.point_j") for e in scene.springs]
        attached += [(e.body, e.point, "loads.point") for e in scene.loads]
        for name, point, key in self.attachments() + attached:
            if name in self.flexible:
                self.flexible[name].interface_at(point, f"{source}: {key}")
        self.points = [(p, index[p.body], self.flexible[p.body].shape_at(
            p.position, f"{source}: output.points.position") if p.body in self.flexible else None)
            for p in scene.output.points]

    def modes(self, name) -> int:
        return self.flexible[name].n if name in self.flexible else 0

    def frame_point(self, name, point) -> list:
        """The point whose frame a drive or torsion element turns: given, or a flexible body's
        first interface (a rigid body's frame is one: its origin)."""
        if point is not None:
            return list(point)
        return list(self.flexible[name].centres[0]) if name in self.flexible else [0.0] * self.DIM

    def offsets(self) -> np.ndarray:
        return self.columns.copy()

    def flex(self) -> np.ndarray:
        """Args.flex: a row per body of its modal constants (rigid: zero)."""
        rows = [self.constants(self.flexible[b.name]) if b.name in self.flexible else np.zeros(3)
                for b in self.scene.bodies]
        out = np.zeros((len(rows), max(r.size for r in rows)))
        for b, r in enumerate(rows):
            out[b, :r.size] = r
        return out

    def strain_energy(self, names, q) -> np.ndarray:
        """The flexible bodies' strain energy at the steps, sum of omega_j^2 eta_j^2 / 2 (J)
        (q: coordinates per step; a body's modal coordinates after its rigid ones)."""
        energy = np.zeros(q.shape[0])
        for b, name in enumerate(names):
            if name in self.flexible:
                f = self.flexible[name]
                c = self.coordinate(b) + self.RIGID_COORDINATES
                energy += 0.5 * (q[:, c:c + f.n] ** 2) @ f.body.omega[:f.n] ** 2
        return energy


def rigid_twin(data: dict, base=None) -> dict:
    """A scene's data (a dict as read from its TOML) with each flexible body rigid: the mass
    and the inertia about the centre of mass of its modes file (a plane body's about z). The
    body's frame is at its centre of mass in both, so its joints' points, its position and
    its rotation stay; output points on it go (a rigid body has no elastic displacement).
    What flexibility costs and changes is then the difference of the two runs, everything
    else (joints, laws, tolerances) the same. `base`: the directory a relative modes_file is
    read from."""
    twin = json.loads(json.dumps(data))
    rigid = set()
    for i, b in enumerate(twin["bodies"]):
        if "modes_file" not in b:
            continue
        path = Path(b["modes_file"])
        body = modes_file.read(path if path.is_absolute() or base is None else Path(base) / path)
        inertia = body.inertia.tolist() if body.dim == 3 else float(body.inertia[2, 2])
        twin["bodies"][i] = {k: v for k, v in b.items() if k not in FLEXIBLE_KEYS} | {
            "mass": float(body.mass), "inertia": inertia}
        rigid.add(b["name"])
    output = twin.get("output", {})
    if "points" in output:
        output["points"] = [p for p in output["points"] if p["body"] not in rigid]
    return twin
