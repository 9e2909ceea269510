"""Linear elasticity of the two bodies, plane strain (2D) or 3D, the way a DOLFINx demo
writes it.

Small strain, isotropic, each body with its own (E, nu):

    sigma(u) = lambda tr(eps(u)) I + 2 mu eps(u),   eps(u) = sym(grad u),
    a(u, v)  = int_Omega sigma(u) : eps(v) dx          (2D: per unit thickness, N/m)

Plane strain keeps eps_zz = 0, so sigma_zz = nu (sigma_xx + sigma_yy); the von Mises stress
includes it. Boundary conditions: the hub (the pin's bore) moves rigidly, the housing's outer
surface is clamped, the 3D ends are free, and a 3D half model holds u_z = 0 on its plane of
symmetry. The stiffness is linear and assembled once; the contact terms are added to it at
every Newton iteration.
"""

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from pinbore.meshes.model import BORE_SURFACE, HOUSING, HOUSING_EDGE, HUB, PIN, PIN_SURFACE, SYMMETRY


def lame(E: float, nu: float) -> tuple[float, float]:
    """Lame constants (Pa): lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu))."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def piecewise(mesh, cell_tags, values: dict[int, float]) -> dolfinx.fem.Function:
    """A DG0 function equal to values[tag] on the cells tagged `tag`."""
    Q = dolfinx.fem.functionspace(mesh, ("DG", 0))
    f = dolfinx.fem.Function(Q)
    for tag, value in values.items():
        f.x.array[cell_tags.find(tag)] = value
    f.x.scatter_forward()
    return f


class Elasticity:
    """Space, stiffness matrices and boundary dofs of the pin-in-bore model."""

    def __init__(self, mesh, cell_tags, facet_tags, pin_material, bore_material, tilt_frame=None):
        """tilt_frame (3D): (pivot c, unit axis a) of the hub's tilt and of the moment taken
        about it (rigid_motion)."""
        self.mesh = mesh
        self.tilt_frame = tilt_frame
        self.dim = dim = mesh.geometry.dim
        self.V = V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (dim,)))
        lam_pin, mu_pin = lame(pin_material.E, pin_material.nu)
        lam_bore, mu_bore = lame(bore_material.E, bore_material.nu)
        self.lmbda = piecewise(mesh, cell_tags, {PIN: lam_pin, HOUSING: lam_bore})
        self.mu = piecewise(mesh, cell_tags, {PIN: mu_pin, HOUSING: mu_bore})

        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        self.a = dolfinx.fem.form(ufl.inner(self.sigma(u), self.epsilon(v)) * ufl.dx)

        fdim = mesh.topology.dim - 1
        mesh.topology.create_connectivity(fdim, mesh.topology.dim)
        self.dofs = {name: dolfinx.fem.locate_dofs_topological(V, fdim, facet_tags.find(tag))
                     for name, tag in (("hub", HUB), ("housing_edge", HOUSING_EDGE),
                                       ("pin_surface", PIN_SURFACE), ("bore_surface", BORE_SURFACE))}
        self.pin_nodes = dolfinx.fem.locate_dofs_topological(V, mesh.topology.dim, cell_tags.find(PIN))
        self.hub_motion = dolfinx.fem.Function(V)
        self.hub_X = V.tabulate_dof_coordinates()[self.dofs["hub"], :dim]
        self.bcs = [dolfinx.fem.dirichletbc(self.hub_motion, self.dofs["hub"]),
                    dolfinx.fem.dirichletbc(np.zeros(dim), self.dofs["housing_edge"], V)]
        self.symmetric = bool(mesh.comm.allreduce(int(SYMMETRY in facet_tags.values), op=MPI.MAX))
        if self.symmetric:
            axial = V.sub(2)
            plane = dolfinx.fem.locate_dofs_topological(axial, fdim, facet_tags.find(SYMMETRY))
            self.bcs.append(dolfinx.fem.dirichletbc(0.0, plane, axial))

        # K: full stiffness, for residuals and reactions. K_bc: rows and columns of prescribed
        # dofs replaced by the identity, the Jacobian of the constrained problem.
        self.K = dolfinx.fem.petsc.assemble_matrix(self.a)
        self.K.assemble()
        self.K_bc = dolfinx.fem.petsc.assemble_matrix(self.a, bcs=self.bcs)
        self.K_bc.assemble()

    def epsilon(self, u):
        return ufl.sym(ufl.grad(u))

    def sigma(self, u):
        return (self.lmbda * ufl.tr(self.epsilon(u)) * ufl.Identity(self.dim)
                + 2 * self.mu * self.epsilon(u))

    def von_mises(self, u) -> ufl.core.expr.Expr:
        """sqrt(3/2 s:s), s the deviatoric stress; plane strain with sigma_zz = nu
        (sigma_xx + sigma_yy)."""
        if self.dim == 3:
            s3 = ufl.dev(self.sigma(u))
            return ufl.sqrt(1.5 * ufl.inner(s3, s3))
        s2 = self.sigma(u)
        nu = self.lmbda / (2 * (self.lmbda + self.mu))
        s_zz = nu * ufl.tr(s2)
        mean = (ufl.tr(s2) + s_zz) / 3
        dev2 = s2 - mean * ufl.Identity(2)
        return ufl.sqrt(1.5 * (ufl.inner(dev2, dev2) + (s_zz - mean) ** 2))

    @property
    def num_dofs(self) -> int:
        imap = self.V.dofmap.index_map
        return imap.size_global * self.V.dofmap.index_map_bs

    def set_boundary_values(self, x: PETSc.Vec, shift, rotation: float = 0.0,
                            tilt: float = 0.0) -> None:
        """Write the prescribed values into x: the hub moves rigidly, translated by `shift`
        (m), turned by `rotation` and tilted by `tilt` (rad, linearised: rigid_motion about
        self.tilt_frame), the outer edge stays clamped."""
        self.hub_motion.x.array.reshape(-1, self.dim)[self.dofs["hub"]] = rigid_motion(
            self.hub_X, shift, rotation, tilt, self.tilt_frame)
        dolfinx.fem.petsc.set_bc(x, self.bcs)

    def pin_rigid_motion(self, shift, rotation: float = 0.0, tilt: float = 0.0) -> PETSc.Vec:
        """A vector that moves every pin node rigidly (see set_boundary_values), the housing
        at rest."""
        f = dolfinx.fem.Function(self.V)
        X = self.V.tabulate_dof_coordinates()[self.pin_nodes, :self.dim]
        f.x.array.reshape(-1, self.dim)[self.pin_nodes] = rigid_motion(X, shift, rotation, tilt,
                                                                       self.tilt_frame)
        return f.x.petsc_vec.copy()

    def prescribed_rows(self) -> np.ndarray:
        """Global rows of the prescribed dofs owned by this rank."""
        imap, bs = self.V.dofmap.index_map, self.V.dofmap.index_map_bs
        local = [bc.dof_indices()[0][:bc.dof_indices()[1]] for bc in self.bcs]
        return (imap.local_range[0] * bs + np.unique(np.concatenate(local))).astype(PETSc.IntType)

    def zero_prescribed(self, F: PETSc.Vec) -> None:
        """F = 0 at the prescribed dofs (their values are set, not solved for)."""
        dolfinx.fem.petsc.set_bc(F, self.bcs, alpha=0.0)

    # --- the material interface of the load stepper (fem.solver) and of the impact's time
    # integrator (fem.impact.solver), shared with fem.plasticity.ElastoPlastic; linear elasticity
    # has a constant tangent and no state

    plastic = False

    def internal_force(self, x: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = K x: the elastic internal forces (N/m per dof)."""
        self.K.mult(x, out)

    def add_tangent(self, x: PETSc.Vec, J: PETSc.Mat) -> None:
        """J += K_bc (the stiffness with identity rows and columns at the prescribed dofs;
        J's pattern holds K_bc's)."""
        J.axpy(1.0, self.K_bc, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def tangent(self, x: PETSc.Vec) -> PETSc.Mat:
        """d f_int / d x with no rows replaced (a time integrator that reduces the hub to a
        rigid body, fem.impact.solver): the stiffness K, constant."""
        return self.K

    def elastic_energy(self, x: PETSc.Vec) -> float:
        """The stored elastic energy x . K x / 2 (J/m in 2D, J in 3D)."""
        Kx = self.K.createVecLeft()
        self.K.mult(x, Kx)
        energy = 0.5 * Kx.dot(x)
        Kx.destroy()
        return energy

    def commit(self, x: PETSc.Vec) -> float:
        """No state to keep; the plastic work of the step: 0 (J/m)."""
        return 0.0

    def snapshot(self):
        return None

    def restore(self, snapshot) -> None:
        pass

    def max_plastic_strain(self) -> float:
        return 0.0

    def hub_reaction(self, forces: PETSc.Vec) -> tuple[np.ndarray, float]:
        """Force (N/m in 2D, N in 3D) the hub exerts on the pin, summed over its dofs, from
        the internal forces `forces` (K x, or those of an elasto-plastic material) at the hub;
        and (3D) its moment (N m) about the tilt axis through the tilt pivot
        (self.tilt_frame), sum (X - c) x f . a over the hub's nodes at their reference
        positions X (small strain: the internal forces have no moment over a free body, so
        this is also minus the moment of the contact tractions; 0.0 in 2D)."""
        local = forces.getArray(readonly=True).reshape(-1, self.dim)
        hub = self.dofs["hub"]
        mine = hub < self.V.dofmap.index_map.size_local
        forces = local[hub[mine]]
        moment = 0.0
        if self.tilt_frame is not None:
            pivot, axis = (np.asarray(v, dtype=float) for v in self.tilt_frame)
            moment = float(np.sum(np.cross(self.hub_X[mine] - pivot, forces) @ axis))
        total = self.mesh.comm.allreduce(np.append(forces.sum(axis=0), moment))
        return total[:self.dim], float(total[self.dim])


def rigid_motion(X: np.ndarray, shift, rotation: float, tilt: float = 0.0, frame=None) -> np.ndarray:
    """Small-strain rigid motion of points X (n, 2 or 3):

        u = shift + rotation e_z x X + tilt a x (X - c),

    a turn about the z axis (the pin's axis in the reference configuration) and, in 3D, a
    tilt about the unit axis a through the point c, `frame` = (c, a) (fem.scene.FemScene's
    tilt_pivot and tilt_axis)."""
    turn = np.zeros_like(X)
    turn[:, 0], turn[:, 1] = -X[:, 1], X[:, 0]
    u = np.asarray(shift) + rotation * turn
    if tilt:
        pivot, axis = (np.asarray(v, dtype=float) for v in frame)
        u = u + tilt * np.cross(axis, X - pivot)
    return u
