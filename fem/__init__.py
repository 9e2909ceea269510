"""DOLFINx finite elements of the pin in its bore. The quasi-static contact (`pinbore fem`):
the scene, elasticity, elasto-plasticity, the contact with Coulomb friction (penalty or
augmented Lagrangian), the load stepper, the quantities read off a state and the curve files
(curve.csv, pressure.csv); the room `impact/`: the dynamic impact of the pin in its bore
(`pinbore impact`); the room `modes/`: a body's modal reduction to a flexible body with
SLEPc (`pinbore modes`)."""

import os

# PETSc's own signal handler turns SIGTERM into MPI_Abort, which leaves a run's outputs half
# written; without it, pinbore.core.output removes them and the CLI says so in one line.
# (Read by PetscInitialize, so it is set before this package loads PETSc.)
if "-no_signal_handler" not in os.environ.get("PETSC_OPTIONS", ""):
    os.environ["PETSC_OPTIONS"] = f"{os.environ.get('PETSC_OPTIONS', '')} -no_signal_handler".strip()

if __name__ != "pinbore.fem":   # one module, one name: never a second copy as `fem`
    raise ImportError("fem/ is the package pinbore.fem: import pinbore.fem")
