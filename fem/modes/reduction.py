r"""A body's FE model reduced to a flexible body of a mechanism: modes, frequencies and the
floating frame's inertia invariants, from the assembled M and K.

The FE model (the way a DOLFINx demo writes it), Lagrange of degree p, small strain:

    K:  a(u, v) = t int sigma(u) : eps(v) dx,   sigma = lambda tr(eps) I + 2 mu eps
    M:  m(u, v) = t int rho u . v dx
    (3D: t = 1; dim = 2: plane stress, t the thickness, lambda* = 2 lambda mu / (lambda + 2 mu))

**Interfaces, rigid.** A joint's interface (a bore, an end face) is tied rigidly to the
frame at its centre (an RBE2 condition): its nodes move as u = t + theta x (x - x_c), so the
frame's R = 3 (plane) or 6 (space) coordinates replace them. Rigid, not averaging, because the
bore's local compliance is the contact law's: pinbore calibrates its contact laws on FE models
of the pin in its bore (fem, calibration), so that compliance is in the law; a bore free to
ovalise in the modes as well would count it twice. The body's own bending, stretching and
twisting between its interfaces is what the modes carry.

**Craig-Bampton** [CraigBampton1968]. With the interfaces' frames held (u_B = 0), the
fixed-interface normal modes Phi_f of (K_II, M_II) (SLEPc, shift-invert about 0: K_II is
positive definite once a frame is held), and the constraint modes Phi_c = -K_II^-1 K_IB, the
static shape of a unit motion of each frame coordinate. Chosen over free-interface modes with
residual attachment modes because the joints act at few, known interfaces: a constraint mode
per interface coordinate represents exactly the static deformation the joint loads cause
(free-interface modes need the residual flexibility for that), and a cantilevered appendage's
fixed-interface modes are its physical modes. The basis B = [Phi_f, Phi_c] holds the body's
rigid-body motions exactly (a rigid motion of the frames' coordinates is a rigid motion of
the body: K's null space).

**The reduced body's free modes.** Its M_r = B^T M B, K_r = B^T K B (dense, small) have R
zero eigenvalues (the rigid motions, checked) and n flexible ones: the body keeps the lowest
n, Psi = B V, M-orthonormal (Psi^T M Psi = I, Psi^T K Psi = diag(omega^2)) and M-orthogonal
to the rigid motions: the floating frame is Buckens' mean-axis frame [Shabana2005], its origin
at the centre of mass that the deformation does not move (1^T M Psi = 0) and its axes those
the deformation does not turn (sum x x Psi: x~^T M Psi = 0).

**Inertia invariants from M** [ZwoelferGerstmayr2021]. With the scalar mass matrix M_s = the
x-block of M (M is rho u . v: each component's block is the same), the nodes' coordinates X
(from the centre of mass; the rigid fields interpolated exactly on an affine mesh) and the
modes' components Psi_a (node values of component a):

    m = 1^T M_s 1,   I_ab = X_a^T M_s X_b,   s_ab = X_a^T M_s Psi_b,   S_ab = Psi_a^T M_s Psi_b

(a, b in x, y, z; a plane body's z entries are zero). Every inertia term of the floating frame
(the deformed body's inertia tensor, the rotation-mode coupling, the quadratic velocity
terms) is a sum of these.

**Geometric stiffening** [WallrappSchwertassek1991]. The linear modes lose the stiffening of
the stress a fast-turning body carries (a spinning beam's bending stiffness grows with the
centrifugal tension; without it the deflection grows without bound past the first
frequency). For each product w_a w_b of the angular velocity, the centrifugal body force
rho (delta_ab r_i - (delta_ia r_b + delta_ib r_a) / 2), r = x - x_root from the centre of
the first interface of reduction.stiffening_held (default: the first interface; the body
turning about its root, as an appendage about its hinge), is carried by those interfaces
held (a link turning about one end is not held at the other: held at both, the centrifugal
tension of a uniform bar would turn to compression over its outer part); its stress
sigma_ab gives the geometric stiffness

    K_G,ab = Psi^T G(sigma_ab) Psi,   G(sigma)(u, v) = t int (grad u sigma) : grad v dx

and the body's modal stiffness is diag(omega^2) + sum_ab w_a w_b K_G,ab. (A plane body turns
about z only: K_G,zz.) The stress of the angular acceleration and of the frame's translation
is left out (a first-order effect on the stiffness the spin-up does not need).

Serial (COMM_SELF): a body's reduction is small next to the contact models.
"""

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import time
from dataclasses import dataclass, field

import dolfinx
import dolfinx.fem
import dolfinx.io.gmsh
import dolfinx.mesh
import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.spatial
import ufl
from mpi4py import MPI
from petsc4py import PETSc
from slepc4py import SLEPc

from pinbore.core.errors import InputError
from pinbore.fem.elasticity import lame
from pinbore.fem.modes.scene import ModesScene
from pinbore.meshes import body as body_mesh
from pinbore.meshes.model import gmsh_session

RIGID_ZERO = 1e-6      # a rigid mode's eigenvalue, of the first flexible one, at most
EIGEN_TOLERANCE = 1e-10


def lame_plane_stress(E: float, nu: float, dim: int) -> tuple[float, float]:
    """Lame constants (Pa, fem.elasticity.lame); in plane stress (dim = 2) lambda* =
    2 lambda mu / (lambda + 2 mu) = E nu / (1 - nu^2)."""
    lam, mu = lame(E, nu)
    if dim == 2:
        lam = 2 * lam * mu / (lam + 2 * mu)
    return lam, mu


def mesh_of(scene: ModesScene, comm=MPI.COMM_SELF):
    """The body's DOLFINx mesh, meshed by Gmsh (meshes.body)."""
    with gmsh_session() as gmsh:
        body_mesh.build(gmsh, scene.body)
        data = dolfinx.io.gmsh.model_to_mesh(gmsh.model, comm, 0, gdim=scene.body.dim)
    return data.mesh


class FEBody:
    """Space and matrices (scipy CSR) of a body: V, K, M, the nodes X (mesh frame)."""

    def __init__(self, mesh, scene: ModesScene):
        self.mesh, self.scene = mesh, scene
        self.dim = dim = mesh.geometry.dim
        mat = scene.material
        self.t = scene.body.thickness if dim == 2 else 1.0
        self.V = V = dolfinx.fem.functionspace(mesh, ("Lagrange", scene.reduction.degree, (dim,)))
        self.lam, self.mu = lame_plane_stress(mat.E, mat.nu, dim)
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        t = self.t
        self.K = self._assemble(t * ufl.inner(self.sigma(u), self.epsilon(v)) * ufl.dx)
        self.M = self._assemble(t * mat.density * ufl.inner(u, v) * ufl.dx)
        self.X = V.tabulate_dof_coordinates()[:, :dim].copy()   # one row a node
        self.nodes = self.X.shape[0]

    def _assemble(self, form) -> sp.csr_matrix:
        A = dolfinx.fem.assemble_matrix(dolfinx.fem.form(form)).to_scipy()
        A = A.tocsr()
        A.sort_indices()
        return A

    @staticmethod
    def epsilon(u):
        return ufl.sym(ufl.grad(u))

    def sigma(self, u):
        eps = self.epsilon(u)
        return self.lam * ufl.tr(eps) * ufl.Identity(self.dim) + 2 * self.mu * eps

    def interface_nodes(self, name: str) -> np.ndarray:
        """The nodes on interface `name`'s surface (its facets, found by the geometry)."""
        mesh = self.mesh
        fdim = mesh.topology.dim - 1
        mesh.topology.create_connectivity(fdim, mesh.topology.dim)
        facets = dolfinx.mesh.locate_entities_boundary(
            mesh, fdim, lambda x: self.scene.body.interface_at(name, x[:self.dim]))
        nodes = dolfinx.fem.locate_dofs_topological(self.V, fdim, facets)
        if nodes.size == 0:
            raise InputError(f"reduction.interfaces: {name!r}: no facet of the mesh lies on its "
                             "surface")
        return np.sort(nodes)

    def geometric_stiffness(self, displacement: np.ndarray) -> sp.csr_matrix:
        """G(sigma(u))(w, v) = t int (grad w sigma) : grad v dx for the stress of the
        displacement field u (node values)."""
        u0 = dolfinx.fem.Function(self.V)
        u0.x.array[:] = displacement
        w, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        return self._assemble(self.t * ufl.inner(ufl.grad(w) * self.sigma(u0), ufl.grad(v)) * ufl.dx)


def node_dofs(nodes: np.ndarray, dim: int) -> np.ndarray:
    """The dofs of `nodes` in the vector space (node i's component c: i dim + c)."""
    return (nodes[:, None] * dim + np.arange(dim)).ravel()


def rigid_tie(X: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(dim n, R): the displacement of n nodes X (n, dim) moving with a frame at `centre`:
    u = t + theta x (x - x_c), columns (t, theta): 2D (t_x, t_y, theta_z), 3D (t, theta)."""
    n, dim = X.shape
    r = X - centre[:dim]
    if dim == 2:
        G = np.zeros((n, 2, 3))
        G[:, 0, 0] = G[:, 1, 1] = 1.0
        G[:, 0, 2], G[:, 1, 2] = -r[:, 1], r[:, 0]
        return G.reshape(2 * n, 3)
    G = np.zeros((n, 3, 6))
    G[:, [0, 1, 2], [0, 1, 2]] = 1.0
    # theta x r = -r~ theta
    G[:, 0, 4], G[:, 0, 5] = r[:, 2], -r[:, 1]
    G[:, 1, 3], G[:, 1, 5] = -r[:, 2], r[:, 0]
    G[:, 2, 3], G[:, 2, 4] = r[:, 1], -r[:, 0]
    return G.reshape(3 * n, 6)


def _petsc(A: sp.csr_matrix) -> PETSc.Mat:
    A = sp.csr_matrix(A)
    A.sort_indices()
    mat = PETSc.Mat().createAIJ(size=A.shape, comm=PETSc.COMM_SELF,
                                csr=(A.indptr.astype(PETSc.IntType),
                                     A.indices.astype(PETSc.IntType), A.data))
    mat.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    mat.assemble()
    return mat


@dataclass
class Eigen:
    """The lowest eigenpairs of K x = lambda M x and the factored K - shift M (a KSP)."""

    values: np.ndarray      # lambda = omega^2 (1/s^2), ascending
    vectors: np.ndarray     # (n dofs, count)
    ksp: PETSc.KSP = field(repr=False)
    held: tuple = field(repr=False, default=())   # the solver and matrices the KSP lives on


def unresolved(scene: ModesScene, what: str) -> InputError:
    """The error of a reduction that came out unphysical: what, and the keys that decide it
    (a body far thinner than its cells is ill-conditioned: its stiffness loses positive
    definiteness in the round-off)."""
    b = scene.body
    bore = next((f", body.{k} {getattr(b, k):g} m" for k in ("eye_radius", "lug_bore_radius")
                 if getattr(b, k) is not None), "")
    return InputError(f"body: the reduction is not physical ({what}): the mesh does not resolve "
                      f"the body (body.cell_size {b.cell_size:g} m against body.thickness "
                      f"{b.thickness:g} m{bore}, body.dim {b.dim})")


def lowest_modes(K: sp.csr_matrix, M: sp.csr_matrix, count: int, shift: float,
                 where: str) -> Eigen:
    """The `count` eigenpairs of (K, M) nearest `shift` (SLEPc Krylov-Schur, shift-invert,
    MUMPS), ascending, M-normalised. Fewer converged is an error naming `where`."""
    Kp, Mp = _petsc(K), _petsc(M)
    eps = SLEPc.EPS().create(PETSc.COMM_SELF)
    eps.setOperators(Kp, Mp)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(count, max(2 * count, count + 16))
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(shift)
    eps.setTolerances(EIGEN_TOLERANCE, 500)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(shift)
    ksp = st.getKSP()
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType("mumps")
    eps.solve()
    found = eps.getConverged()
    if found < count:
        raise InputError(f"{where}: SLEPc found {found} of the {count} eigenpairs asked for "
                         f"(reason {eps.getConvergedReason()}): fewer modes "
                         "(reduction.fixed_interface_modes, reduction.full_modes), or a finer mesh "
                         "(body.cell_size)")
    values = np.empty(found)
    vectors = np.empty((K.shape[0], found))
    vr = Kp.createVecRight()
    for k in range(found):
        values[k] = eps.getEigenpair(k, vr).real
        vectors[:, k] = vr.getArray()
    order = np.argsort(values)[:count]
    vectors = vectors[:, order]
    vectors /= np.sqrt(np.einsum("ik,ik->k", vectors, M @ vectors))
    return Eigen(values[order], vectors, ksp, (eps, Kp, Mp))


def solve_with(ksp: PETSc.KSP, rhs: np.ndarray) -> np.ndarray:
    """The KSP's operator solved for each column of rhs."""
    b = PETSc.Vec().createSeq(rhs.shape[0], comm=PETSc.COMM_SELF)
    x = b.duplicate()
    out = np.empty_like(rhs)
    for k in range(rhs.shape[1]):
        b.setArray(rhs[:, k])
        ksp.solve(b, x)
        out[:, k] = x.getArray()
    return out


@dataclass
class Reduced:
    """The reduced body, in the mesh frame until `frame` moves it to the centre of mass.

    Shapes: n the flexible modes kept, N the nodes, R = 3 (plane) or 6 (space)."""

    dim: int
    mass: float                      # kg
    centre: np.ndarray               # (3,) centre of mass, mesh frame (m)
    X: np.ndarray                    # (N, 3) nodes from the centre of mass (m)
    omega: np.ndarray                # (n,) rad/s
    psi: np.ndarray                  # (N, 3, n) M-normalised modes (m/sqrt(kg))
    second_moments: np.ndarray       # (3, 3) I_ab = X_a^T M_s X_b (kg m^2)
    s: np.ndarray                    # (3, 3, n) s_ab = X_a^T M_s Psi_b
    S: np.ndarray                    # (3, 3, n, n) S_ab = Psi_a^T M_s Psi_b
    translation_coupling: np.ndarray  # (3, n) 1^T M_s Psi_a (mean axes: zero)
    stiffening: np.ndarray           # (3, 3, n, n) K_G,ab (per (rad/s)^2)
    interfaces: list[str]
    interface_centres: np.ndarray    # (k, 3) from the centre of mass (m)
    interface_translation: np.ndarray  # (k, 3, n) each mode's motion of the interface frame
    interface_rotation: np.ndarray   # (k, 3, n) and its rotation (rad per unit coordinate)
    fixed_interface_omega: np.ndarray  # (n_f,) rad/s
    rigid_residual: float            # the largest rigid eigenvalue / the first flexible one
    full_omega: np.ndarray           # (full_modes,) the whole FE model's free modes (its
                                     # interfaces tied as the reduction ties them), rad/s
    cells: np.ndarray                # (c, vertices) the mesh's cells (node indices of X)
    dofs: int                        # of the FE model
    seconds: dict                    # time of each step (s)


def _pad(a: np.ndarray, dim: int) -> np.ndarray:
    """Vectors of `dim` components (on axis 1) as three."""
    shape = list(a.shape)
    shape[1] = 3
    out = np.zeros(shape)
    out[:, :dim] = a
    return out


def _as_axes(a: np.ndarray, axes) -> np.ndarray:
    """Rows of an interface frame's coordinates (one row a coordinate, a column a mode) as the
    three rows of x, y, z: row k of `a` is axis axes[k] (the others zero)."""
    out = np.zeros((3, a.shape[1]))
    out[list(axes)] = a
    return out


def rigid_interfaces(fe: FEBody, scene: ModesScene) -> tuple[np.ndarray, sp.csr_matrix]:
    """The dofs not on an interface, and T_B (dofs, R k): each interface's nodes moving
    rigidly with its frame (R coordinates each, in the order of reduction.interfaces)."""
    dim, R = fe.dim, scene.rigid
    names = scene.reduction.interfaces
    rows, blocks = [], []
    for name in names:
        nodes = fe.interface_nodes(name)
        rows.append(node_dofs(nodes, dim))
        blocks.append(rigid_tie(fe.X[nodes], np.asarray(scene.body.interfaces[name])))
    boundary = np.concatenate(rows)
    if np.unique(boundary).size != boundary.size:
        raise InputError("reduction.interfaces: two interfaces share nodes of the mesh")
    n_dofs = fe.nodes * dim
    TB = sp.lil_matrix((n_dofs, R * len(names)))
    for k, (dofs, G) in enumerate(zip(rows, blocks)):
        TB[dofs, R * k:R * (k + 1)] = G
    return np.setdiff1d(np.arange(n_dofs), boundary), TB.tocsr()


def craig_bampton(fe: FEBody, scene: ModesScene, interior: np.ndarray,
                  TB: sp.csr_matrix) -> tuple[Eigen, np.ndarray]:
    """The fixed-interface modes (an Eigen of (K_II, M_II), its KSP the factored K_II) and
    the constraint modes -K_II^-1 K_IB T_B (interior dofs, R k)."""
    K, M = fe.K, fe.M
    K_II, M_II = K[interior][:, interior], M[interior][:, interior]
    fixed = lowest_modes(K_II, M_II, scene.reduction.fixed_interface_modes, 0.0,
                         "the fixed-interface modes")
    return fixed, -solve_with(fixed.ksp, (K[interior] @ TB).toarray())


def reduce(scene: ModesScene, fe: FEBody | None = None, progress=None) -> Reduced:
    """The reduced body of `scene` (its FE model built unless given)."""
    clock = time.perf_counter()
    seconds = {}
    fe = fe or FEBody(mesh_of(scene), scene)
    seconds["mesh_and_assembly"] = time.perf_counter() - clock
    if progress:
        progress.update(1)
    dim, R = fe.dim, scene.rigid
    names = scene.reduction.interfaces
    centres = np.array([scene.body.interfaces[name] for name in names])
    clock = time.perf_counter()
    interior, TB = rigid_interfaces(fe, scene)
    K, M = fe.K, fe.M
    n_dofs = fe.nodes * dim
    fixed, constraint = craig_bampton(fe, scene, interior, TB)
    seconds["fixed_interface_modes"] = time.perf_counter() - clock
    if progress:
        progress.update(1)

    # the Craig-Bampton basis in the whole model's dofs, and the reduced body's free modes
    clock = time.perf_counter()
    n_f = fixed.vectors.shape[1]
    B = np.zeros((n_dofs, n_f + R * len(names)))
    B[interior, :n_f] = fixed.vectors
    B[interior, n_f:] = constraint
    B[:, n_f:] += TB.toarray()
    Kr, Mr = B.T @ (K @ B), B.T @ (M @ B)
    Kr, Mr = (Kr + Kr.T) / 2, (Mr + Mr.T) / 2
    lam, V = scipy.linalg.eigh(Kr, Mr)
    if not (np.all(np.isfinite(lam)) and lam[R] > 0):
        raise unresolved(scene, f"the reduced body's first flexible eigenvalue is {lam[R]:.3g} 1/s^2")
    rigid_residual = float(np.max(np.abs(lam[:R])) / lam[R])
    if not rigid_residual <= RIGID_ZERO:
        raise unresolved(scene, f"its {R} rigid-body motions are not free: the largest of their "
                                f"eigenvalues is {rigid_residual:.2g} of the first flexible one")
    n = scene.reduction.modes
    keep = V[:, R:R + n]
    psi_dofs = B @ keep
    omega = np.sqrt(lam[R:R + n])
    seconds["reduced_modes"] = time.perf_counter() - clock

    # the floating frame: centre of mass, invariants from M
    Ms = M[0::dim, 0::dim]
    ones = np.ones(fe.nodes)
    mass = float(ones @ (Ms @ ones))
    centre = (fe.X.T @ (Ms @ ones)) / mass
    X = _pad(fe.X - centre, dim)
    psi = _pad(psi_dofs.reshape(fe.nodes, dim, n), dim)
    MsX = Ms @ X
    MsPsi = np.stack([Ms @ psi[:, a, :] for a in range(3)], axis=1)   # (N, 3, n)
    second = X.T @ MsX
    s = np.einsum("ia,ibk->abk", X, MsPsi)
    S = np.einsum("iak,ibl->abkl", psi, MsPsi)
    translation = np.einsum("i,iak->ak", ones, MsPsi)
    centre3 = np.append(centre, [0.0] * (3 - dim))
    frames = keep[n_f:].reshape(len(names), R, n)
    turning = (2,) if dim == 2 else (0, 1, 2)   # a plane body's frame turns about z alone
    interface_translation = np.stack([_as_axes(f[:dim], range(dim)) for f in frames])
    interface_rotation = np.stack([_as_axes(f[dim:], turning) for f in frames])

    clock = time.perf_counter()
    if set(scene.held) == set(names):
        ksp, free = fixed.ksp, interior
    else:   # only some interfaces carry the load: K factored with those held alone
        held = np.concatenate([node_dofs(fe.interface_nodes(name), dim) for name in scene.held])
        free = np.setdiff1d(np.arange(n_dofs), held)
        ksp, _ = factored(K[free][:, free])
    root = np.asarray(scene.body.interfaces[scene.held[0]])
    stiffening = geometric_stiffening(fe, ksp, free, psi_dofs, root)
    seconds["stiffening"] = time.perf_counter() - clock
    if progress:
        progress.update(1)

    clock = time.perf_counter()
    full = np.empty(0)
    if scene.reduction.full_modes:
        T = sp.identity(n_dofs, format="csr")[:, interior]
        T = sp.hstack([T, TB], format="csr")
        full = free_modes(T.T @ K @ T, T.T @ M @ T, scene.reduction.full_modes, R, fixed.values[0])
    seconds["full_modes"] = time.perf_counter() - clock
    if progress:
        progress.update(1)

    cells = fe.mesh.geometry.dofmaps[0]   # first-order geometry: the vertices
    vertex_nodes = _vertex_nodes(fe)
    return Reduced(dim=dim, mass=mass, centre=centre3, X=X, omega=omega, psi=psi,
                   second_moments=second, s=s, S=S, translation_coupling=translation,
                   stiffening=stiffening, interfaces=list(names),
                   interface_centres=centres - centre3,
                   interface_translation=interface_translation,
                   interface_rotation=interface_rotation,
                   fixed_interface_omega=np.sqrt(fixed.values), rigid_residual=rigid_residual,
                   full_omega=full, cells=vertex_nodes[cells], dofs=n_dofs, seconds=seconds)


def _vertex_nodes(fe: FEBody) -> np.ndarray:
    """For each geometry node (the mesh's first-order vertices), its node of V (the dof
    at the same place)."""
    x = fe.mesh.geometry.x[:, :fe.dim]
    tree = scipy.spatial.cKDTree(fe.X)
    distance, index = tree.query(x)
    if np.max(distance) > 1e-9 * fe.scene.body.size:
        raise RuntimeError("a vertex of the mesh is not a node of the FE space")
    return index


def centrifugal_fields(X: np.ndarray, root: np.ndarray, dim: int) -> dict:
    """The body-force fields (per unit density, per (rad/s)^2) of each product w_a w_b of
    the angular velocity, the body turning about `root`: field_ab,i = delta_ab r_i -
    (delta_ia r_b + delta_ib r_a) / 2, r = x - root (so that sum_ab w_a w_b field_ab =
    -w x (w x r)). A plane body turns about z only: (2, 2)."""
    r = np.zeros((X.shape[0], 3))
    r[:, :dim] = X - root[:dim]
    pairs = [(2, 2)] if dim == 2 else [(a, b) for a in range(3) for b in range(a, 3)]
    fields = {}
    for a, b in pairs:
        f = np.zeros((X.shape[0], 3))
        if a == b:
            f += r
        f[:, a] -= r[:, b] / 2
        f[:, b] -= r[:, a] / 2
        fields[a, b] = f[:, :dim]
    return fields


def factored(A: sp.csr_matrix):
    """A KSP that solves with A (MUMPS Cholesky), and the matrix it lives on."""
    mat = _petsc(A)
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(mat)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType("mumps")
    ksp.setUp()
    return ksp, mat


def geometric_stiffening(fe: FEBody, ksp, free, psi_dofs, root) -> np.ndarray:
    """K_G,ab (3, 3, n, n), symmetric in (a, b) (module docstring): the centrifugal load
    cases of the body turning about `root`, solved with `ksp` on the dofs `free` (the
    others held: the interfaces that carry the load)."""
    n = psi_dofs.shape[1]
    out = np.zeros((3, 3, n, n))
    fields = centrifugal_fields(fe.X, root, fe.dim)
    loads = np.column_stack([fe.M @ f.ravel() for f in fields.values()])
    u = np.zeros((fe.nodes * fe.dim, loads.shape[1]))
    u[free] = solve_with(ksp, loads[free])
    for k, (a, b) in enumerate(fields):
        G = fe.geometric_stiffness(u[:, k])
        KG = psi_dofs.T @ (G @ psi_dofs)
        out[a, b] = out[b, a] = (KG + KG.T) / 2
    return out


def free_modes(K: sp.csr_matrix, M: sp.csr_matrix, count: int, rigid: int, scale: float) -> np.ndarray:
    """The lowest `count` flexible free-free frequencies of the model (K, M) (rad/s):
    shift-invert about -scale / 10 (a shift of zero would factor a singular K)."""
    eig = lowest_modes(K, M, count + rigid, -scale / 10, "the whole model's free modes")
    if not (eig.values[rigid] > 0 and np.max(np.abs(eig.values[:rigid])) <= RIGID_ZERO * eig.values[rigid]):
        raise InputError("reduction.full_modes: the whole model's rigid-body motions did not come out "
                         "at zero frequency: the mesh does not resolve the body (body.cell_size "
                         "against body.thickness)")
    return np.sqrt(eig.values[rigid:])

