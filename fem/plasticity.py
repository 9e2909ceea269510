r"""Elasto-plastic bodies: von Mises plasticity with isotropic hardening, small strain, radial
return with the consistent tangent; plane strain (2D) or 3D.

Material (a point of the pin or of the bore)
--------------------------------------------
The strain splits additively, eps = eps_e + eps_p; the stress is elastic in eps_e,

    sigma = kappa tr(eps_e) I + 2 mu dev(eps_e),                kappa = E / (3 (1 - 2 nu)),

the yield function is von Mises' with isotropic hardening [SimoHughes1998] (§2.3, §3.3),

    f(sigma, p) = q - sigma_y(p) <= 0,      q = sqrt(3/2 s : s),  s = dev(sigma),

and the flow is associative, d eps_p = 3/2 dp s / q, so p, the equivalent plastic strain,
grows by sqrt(2/3 d eps_p : d eps_p). sigma_y(p) is piecewise linear: Y + H p (linear
hardening; H = 0 is perfect plasticity), or a table of (p_k, sigma_y,k) from (0, Y), held
constant beyond its last point.

Radial return (backward Euler, [SimoHughes1998] Box 3.2). From the converged state
(eps_p,n, p_n) and the total strain eps of the iterate, the trial stress is elastic,
s_tr = 2 mu dev(eps - eps_p,n), q_tr = sqrt(3/2 s_tr : s_tr). If q_tr <= sigma_y(p_n) the
step is elastic. Otherwise the stress returns along s_tr: with dp > 0 solving

    q_tr - 3 mu dp = sigma_y(p_n + dp)          (one linear equation per segment of the
                                                 table, solved segment after segment),

    s = (1 - 3 mu dp / q_tr) s_tr,   eps_p = eps_p,n + 3/2 dp s_tr / q_tr,   p = p_n + dp.

The consistent (algorithmic) tangent d sigma / d eps of this map, n = s_tr / |s_tr|,
theta = 1 - 3 mu dp / q_tr, H the slope of sigma_y at p ([SimoHughes1998] Box 3.2):

    C = kappa I (x) I + 2 mu theta (I_sym - I (x) I / 3) - 2 mu (3 mu / (3 mu + H) - 1 + theta) n (x) n.

Newton with it converges quadratically (tests/test_plasticity.py checks it against finite
differences of the return map).

Tensors are stored as 6 Mandel components (xx, yy, zz, sqrt2 xy, sqrt2 yz, sqrt2 xz): the
double contraction is the dot product and the tangent a symmetric 6 x 6 matrix. Plane strain
keeps eps_zz = 0 (and eps_yz = eps_xz = 0) in the total strain, while sigma_zz and the
plastic eps_p,zz are computed and kept; the forms use the in-plane components
(xx, yy, sqrt2 xy).

FE discretisation
-----------------
The states (eps_p, p) and the stress live at the quadrature points of the cells (basix
quadrature elements; P1 simplices have a constant strain, so one point per cell integrates
the forms exactly). Each residual evaluation interpolates the strain of the iterate at the
points (dolfinx.fem.Expression), runs the return map (the compiled core, all points at once) and
assembles

    f_int(u) = int sigma(u) : eps(v) dx,      K_t(u) = int eps(du) : C(u) : eps(v) dx,

per unit length in 2D. A converged step is committed: its (eps_p, p, sigma) become the
state the next step returns from. The plastic work of a step is integrated with the
trapezoidal rule, dW_p = int (sigma_n + sigma_n+1)/2 : (eps_p,n+1 - eps_p,n) dx, which makes
the energy book close: the internal work of the step, int (sigma_n + sigma_n+1)/2 : d eps dx,
equals exactly the change of the elastic energy int sigma : C^-1 : sigma / 2 dx plus dW_p
(C^-1 is linear), so the work of the hub over a load-unload loop is the plastic work plus
the elastic energy locked in the residual stresses (tests/test_fem_plasticity.py).

While no point flows at an iterate (every point on the elastic branch of the return map
from the committed state: elastic unloading, free flight, reloading below the reached
yield stress), sigma = C : (eps - eps_p) at every point, so

    f_int(u) = K u - int C : eps_p : eps(v) dx,        K_t = K,

the elastic stiffness assembled once and a force of the committed plastic strains,
assembled once per commit (exact: the consistent tangent of the elastic branch is C). The
load stepper keeps K's factors and a time integrator its cached operator. Measured: in the
study's load-unload-reload cycles (scenes/fem/steel_al6061o_c500um_cycles) 392 of 910
tangents and 627 of 1827 internal forces take K; in a plastic impact almost every Newton
iterate has a flowing point, and little is saved.

P1 triangles and tetrahedra lock under fully plastic (isochoric) flow; a contained plastic
zone under a contact, surrounded by elastic material, is little affected (the first-yield
load is elastic and unaffected), but loads with a plastic zone that breaks through to a free
surface would come out too high.
"""

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import math

import basix.ufl
import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from pinbore.core import cpp
from pinbore.meshes.model import HOUSING, PIN

SQRT2 = np.sqrt(2.0)
IN_PLANE = np.array([0, 1, 3])          # the Mandel components of a plane-strain model
ELASTIC = -1                            # the hardening index of a point that never yields
QUADRATURE_DEGREE = 0                   # P1 simplices: constant strain, one point per cell


# --- the material point: hardening curve and radial return (the compiled core, all points at once)

def radial_return(strain, plastic_strain, equivalent, shear_modulus, bulk_modulus, curve,
                  table_strains, table_stresses, table_counts, table_tails):
    """Von Mises radial return with isotropic hardening at n points (see the module
    docstring for the equations; [SimoHughes1998] Box 3.2), in the compiled core
    (cpp/plasticity.cpp).

    strain, plastic_strain: (n, 6) Mandel components of the total strain of the iterate and
    of the converged plastic strain; equivalent: (n,) converged equivalent plastic strain p;
    shear_modulus, bulk_modulus: (n,) mu and kappa (Pa); curve: (n,) the row of the hardening
    tables of each point (ELASTIC: never yields); table_*: the hardening curves, one row each
    (hardening_tables): sigma_y(p) piecewise linear through the row's points, continued
    beyond its last with slope `tail`.

    Returns the stress (n, 6) (Pa), the plastic strain (n, 6), the equivalent plastic strain
    (n,) and the consistent tangent d sigma / d eps (n, 6, 6) (Pa)."""
    curve, table_counts = np.asarray(curve), np.asarray(table_counts)
    if not (np.issubdtype(curve.dtype, np.integer) and np.issubdtype(table_counts.dtype, np.integer)):
        raise ValueError("radial_return: curve and table_counts are indices (integers)")
    return cpp.radial_return(strain, plastic_strain, equivalent, shear_modulus, bulk_modulus,
                             curve.astype(np.int64), table_strains, table_stresses,
                             table_counts.astype(np.int64), table_tails)


def elastic_energy(stress, shear_modulus, bulk_modulus):
    """Elastic energy density sigma : C^-1 : sigma / 2 (J/m^3) of stresses (n, 6) (Mandel):
    mean stress^2 / (2 kappa) + s : s / (4 mu) (the compiled core)."""
    return cpp.elastic_energy(stress, shear_modulus, bulk_modulus)


def von_mises(stress: np.ndarray) -> np.ndarray:
    """sqrt(3/2 s : s) (Pa) of stresses (n, 6) (Mandel)."""
    mean = stress[:, :3].mean(axis=1, keepdims=True)
    dev = stress.copy()
    dev[:, :3] -= mean
    return np.sqrt(1.5 * np.sum(dev * dev, axis=1))


def table_end(material) -> float:
    """The plastic strain beyond which a material's hardening is not known: the last pair of
    its `hardening` table; none (inf) for the linear law (hardening_modulus, 0 included)."""
    return material.hardening[-1][0] if material.hardening is not None else math.inf


def hardening_tables(curves):
    """The arrays radial_return reads, from hardening curves given as (strains, stresses,
    tail): padded tables (m, k), counts (m,) and tails (m,)."""
    width = max((len(c[0]) for c in curves), default=1)
    strains, stresses = np.full((max(len(curves), 1), width), np.inf), np.zeros((max(len(curves), 1), width))
    strains[:, 0] = 0.0   # every curve starts at p = 0 (the row of no curve too)
    counts, tails = np.ones(max(len(curves), 1), dtype=np.int64), np.zeros(max(len(curves), 1))
    for j, (e, s, tail) in enumerate(curves):
        strains[j, :len(e)], stresses[j, :len(s)], counts[j], tails[j] = e, s, len(e), tail
    return strains, stresses, counts, tails


# --- the FE bodies -----------------------------------------------------------------------------

def mandel(eps, dim: int):
    """The Mandel components of a symmetric UFL tensor: (xx, yy, sqrt2 xy) in 2D, the six in 3D."""
    r2 = float(SQRT2)
    if dim == 2:
        return ufl.as_vector([eps[0, 0], eps[1, 1], r2 * eps[0, 1]])
    return ufl.as_vector([eps[0, 0], eps[1, 1], eps[2, 2], r2 * eps[0, 1], r2 * eps[1, 2],
                          r2 * eps[0, 2]])


class ElastoPlastic:
    """The pin and the bore with von Mises plasticity where their material has a yield stress
    (the other body elastic), on the displacement space of an Elasticity.

    The material interface of the load stepper (fem.solver) and of a time integrator,
    shared with the purely elastic fem.elasticity.Elasticity:
    internal_force(x, out), add_tangent(x, J) (prescribed rows replaced) or tangent(x) (the
    matrix itself), elastic_energy(x), commit(x) -> plastic work of the step,
    snapshot() / restore(s) (the committed state), and the equivalent plastic strain.
    """

    plastic = True

    def __init__(self, elasticity, cell_tags, pin_material, bore_material):
        self.el = el = elasticity
        mesh, dim = el.mesh, el.dim
        self.dim, self.comm = dim, mesh.comm
        self.components = 3 if dim == 2 else 6
        self.taken = IN_PLANE if dim == 2 else np.arange(6)   # form components in the 6
        cell = mesh.basix_cell()
        stress_element = basix.ufl.quadrature_element(cell, value_shape=(self.components,),
                                                       scheme="default", degree=QUADRATURE_DEGREE)
        tangent_element = basix.ufl.quadrature_element(
            cell, value_shape=(self.components, self.components), scheme="default",
            degree=QUADRATURE_DEGREE)
        scalar_element = basix.ufl.quadrature_element(cell, value_shape=(), scheme="default",
                                                      degree=QUADRATURE_DEGREE)
        W = dolfinx.fem.functionspace(mesh, stress_element)
        WT = dolfinx.fem.functionspace(mesh, tangent_element)
        Ws = dolfinx.fem.functionspace(mesh, scalar_element)
        self.stress_q = dolfinx.fem.Function(W)
        self.tangent_q = dolfinx.fem.Function(WT)
        self.u = dolfinx.fem.Function(el.V)

        # the strain of the iterate at the quadrature points
        points = W.element.interpolation_points
        self.strain_expr = dolfinx.fem.Expression(mandel(el.epsilon(self.u), dim), points)
        self.cells = np.arange(mesh.topology.index_map(dim).size_local, dtype=np.int32)
        self.per_cell = points.shape[0]
        self.dofs = W.dofmap.list[self.cells].ravel()          # the points of the owned cells
        self.dofs_T = WT.dofmap.list[self.cells].ravel()

        # f_int = int sigma : eps(v) dx, K_t = int eps(du) : C : eps(v) dx  (Mandel: dot products)
        dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": QUADRATURE_DEGREE,
                                                      "quadrature_scheme": "default"})
        v, du = ufl.TestFunction(el.V), ufl.TrialFunction(el.V)
        eps_v, eps_du = mandel(el.epsilon(v), dim), mandel(el.epsilon(du), dim)
        self.residual_form = dolfinx.fem.form(ufl.inner(self.stress_q, eps_v) * dx)
        self.tangent_form = dolfinx.fem.form(ufl.inner(ufl.dot(self.tangent_q, eps_du), eps_v) * dx)
        self.b = dolfinx.fem.petsc.create_vector(el.V)
        self.K_t = dolfinx.fem.petsc.create_matrix(self.tangent_form)
        self.K_free = None          # the tangent without boundary rows (tangent), on demand
        # the weight of each point (quadrature weight x |det J|; 2D: m^2, the forms per unit length)
        volume = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(ufl.TestFunction(Ws) * dx))
        self.volume = volume.array[Ws.dofmap.list[self.cells].ravel()].copy()
        volume.destroy()

        # the material of each point
        n = self.cells.size * self.per_cell
        curves, index, self.table_ends = [], {}, []
        self.shear_modulus, self.bulk_modulus = np.empty(n), np.empty(n)
        self.curve = np.full(n, ELASTIC, dtype=np.int64)
        for tag, material in ((PIN, pin_material), (HOUSING, bore_material)):
            cells = cell_tags.find(tag)
            cells = cells[cells < self.cells.size]
            points = (cells[:, None] * self.per_cell + np.arange(self.per_cell)).ravel()
            E, nu = material.E, material.nu
            self.shear_modulus[points] = E / (2 * (1 + nu))
            self.bulk_modulus[points] = E / (3 * (1 - 2 * nu))
            if material.yield_stress is not None:
                index[tag] = len(curves)
                curves.append(material.hardening_curve)
                self.table_ends.append(table_end(material))
                self.curve[points] = index[tag]
        self.tables = hardening_tables(curves)

        # the committed state, and the last evaluated iterate
        self.plastic_strain = np.zeros((n, 6))
        self.equivalent = np.zeros(n)
        self.stress = np.zeros((n, 6))
        self.committed = 0          # commits and restores so far (a key of evaluate's cache)
        self._key = self._last = None
        self._elastic = True        # no point flows at the last evaluated iterate
        self._residual, self._residual_key = None, None   # residual_force and its state

    # --- evaluation at an iterate ----------------------------------------------------------

    def strain_at_points(self, x: PETSc.Vec) -> np.ndarray:
        """Mandel components (n, 6) of the strain of the displacement x at the points."""
        x.copy(self.u.x.petsc_vec)
        self.u.x.scatter_forward()
        values = self.strain_expr.eval(self.el.mesh, self.cells).reshape(-1, self.components)
        strain = np.zeros((values.shape[0], 6))
        strain[:, self.taken] = values
        return strain

    def evaluate(self, x: PETSc.Vec):
        """The return map from the committed state at the strain of x: stress, plastic
        strain, equivalent plastic strain, tangent (radial_return). Newton asks for the
        residual and then the tangent at the same iterate: the second call reuses the first
        (keyed on the vector and PETSc's count of its changes)."""
        key = (x.handle, x.stateGet(), self.committed)
        if key != self._key:
            self._key = key
            self._last = radial_return(self.strain_at_points(x), self.plastic_strain,
                                       self.equivalent, self.shear_modulus, self.bulk_modulus,
                                       self.curve, *self.tables)
            flows = bool(np.any(self._last[2] > self.equivalent))
            self._elastic = not self.comm.allreduce(flows, op=MPI.LOR)
        return self._last

    def elastic_everywhere(self, x: PETSc.Vec) -> bool:
        """Whether no point flows at x (every point on the elastic branch of the return map
        from the committed state): then sigma = C : (eps - eps_p) at every point, so
        f_int = K x - int C : eps_p : eps(v) dx, the elastic stiffness K assembled once
        (fem.elasticity) and a force of the committed plastic strains (0 before any flow:
        an impact or a load step that stays below the yield stress is the elastic one to the
        last bit), and the consistent tangent is K itself (theta = 1, beta = 0 at every
        point). Elastic unloading, free flight and reloading after plastic flow so keep K
        (its factors, and a time integrator's cached operator) instead of reassembling the
        tangent at every iterate."""
        self.evaluate(x)
        return self._elastic

    def residual_force(self) -> PETSc.Vec | None:
        """int C : eps_p : eps(v) dx of the committed plastic strains (N/m per dof in 2D, N
        in 3D), the force K x exceeds f_int by while no point flows; None while none has
        flowed. Assembled once per committed state."""
        if self._residual_key != self.committed:
            self._residual_key = self.committed
            if not self.comm.allreduce(bool(np.any(self.equivalent)), op=MPI.LOR):
                self._residual = None
            else:
                # the elastic branch at zero strain: -C : eps_p
                never = np.full_like(self.curve, ELASTIC)
                stress = -radial_return(np.zeros_like(self.plastic_strain), self.plastic_strain,
                                        self.equivalent, self.shear_modulus, self.bulk_modulus,
                                        never, *self.tables)[0]
                if self._residual is None:
                    self._residual = self.b.duplicate()
                self._assemble_force(stress, self._residual)
        return self._residual

    def internal_force(self, x: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = f_int(x) = int sigma(x) : eps(v) dx (N/m per dof in 2D, N in 3D)."""
        if self.elastic_everywhere(x):
            self.el.internal_force(x, out)
            residual = self.residual_force()
            if residual is not None:
                out.axpy(-1.0, residual)
            return
        self._assemble_force(self.evaluate(x)[0], self.b)
        self.b.copy(out)

    def _assemble_force(self, stress: np.ndarray, out: PETSc.Vec) -> None:
        """out = int sigma : eps(v) dx of stresses (n, 6) at the points."""
        self.stress_q.x.array.reshape(-1, self.components)[self.dofs] = stress[:, self.taken]
        with out.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(out, self.residual_form)
        out.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)

    def add_tangent(self, x: PETSc.Vec, J: PETSc.Mat) -> None:
        """J += K_t(x), the consistent tangent, with the prescribed rows and columns replaced
        by the identity (like Elasticity.K_bc; J's pattern holds K_t's)."""
        if self.elastic_everywhere(x):
            self.el.add_tangent(x, J)
            return
        J.axpy(1.0, self._assemble_tangent(x, self.K_t, self.el.bcs),
               structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def tangent(self, x: PETSc.Vec) -> PETSc.Mat:
        """K_t(x) with no rows replaced (a time integrator that reduces the hub to a rigid
        body, fem.impact.solver): the elastic stiffness K itself while no point flows, else a
        matrix the next call overwrites."""
        if self.elastic_everywhere(x):
            return self.el.tangent(x)
        if self.K_free is None:
            self.K_free = dolfinx.fem.petsc.create_matrix(self.tangent_form)
        return self._assemble_tangent(x, self.K_free, [])

    def _assemble_tangent(self, x: PETSc.Vec, K: PETSc.Mat, bcs) -> PETSc.Mat:
        """K = int eps(du) : C(x) : eps(v) dx, the consistent tangent at x (bcs: rows and
        columns replaced by the identity)."""
        tangent = self.evaluate(x)[3][:, self.taken][:, :, self.taken]
        self.tangent_q.x.array.reshape(-1, self.components ** 2)[self.dofs_T] = \
            tangent.reshape(-1, self.components ** 2)
        K.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(K, self.tangent_form, bcs=bcs)
        K.assemble()
        return K

    # --- the committed state ---------------------------------------------------------------

    def commit(self, x: PETSc.Vec) -> float:
        """Make the state at the converged x the one the next step returns from; the plastic
        work of the step (J/m in 2D, J in 3D, of the modelled part), by the trapezoidal rule
        (module docstring)."""
        stress, eps_p, p, _ = self.evaluate(x)
        density = 0.5 * np.einsum("ni,ni->n", self.stress + stress, eps_p - self.plastic_strain)
        self.stress, self.plastic_strain, self.equivalent = stress, eps_p, p
        self.committed += 1
        return self._integral(density)

    def snapshot(self):
        return self.stress.copy(), self.plastic_strain.copy(), self.equivalent.copy()

    def restore(self, snapshot) -> None:
        self.stress, self.plastic_strain, self.equivalent = (a.copy() for a in snapshot)
        self.committed += 1

    def _integral(self, density: np.ndarray) -> float:
        return float(self.comm.allreduce(float(density @ self.volume), op=MPI.SUM))

    def elastic_energy(self, x: PETSc.Vec | None = None) -> float:
        """The stored elastic energy int sigma : C^-1 : sigma / 2 dx of the committed state
        (J/m in 2D, J in 3D, the modelled part); x, the committed displacement, is not
        needed: the committed stresses hold it."""
        return self._integral(elastic_energy(self.stress, self.shear_modulus, self.bulk_modulus))

    def max_plastic_strain(self) -> float:
        """The largest equivalent plastic strain of the committed state."""
        return float(self.comm.allreduce(float(self.equivalent.max(initial=0.0)), op=MPI.MAX))

    def beyond_table(self) -> bool:
        """Whether a point has gone past the last point of its hardening table (held
        constant there: the table does not say what the material does)."""
        mine = any(np.any(self.equivalent[self.curve == j] > end)
                   for j, end in enumerate(self.table_ends))
        return bool(self.comm.allreduce(int(mine), op=MPI.MAX))

    def cell_values(self, name: str) -> np.ndarray:
        """Per owned cell: the cell mean of the committed equivalent plastic strain
        ("equivalent_plastic_strain") or von Mises stress ("von_mises", Pa)."""
        values = self.equivalent if name == "equivalent_plastic_strain" else von_mises(self.stress)
        return values.reshape(-1, self.per_cell).mean(axis=1)

