"""Stage 2: DOLFINx contact between the pin and the bore (penalty or augmented Lagrangian)."""

import os

# PETSc's own signal handler turns SIGTERM into MPI_Abort, which leaves a run's outputs half
# written; without it, pinbore.core.output removes them and the CLI says so in one line.
# (Read by PetscInitialize, so it is set before this package loads PETSc.)
if "-no_signal_handler" not in os.environ.get("PETSC_OPTIONS", ""):
    os.environ["PETSC_OPTIONS"] = f"{os.environ.get('PETSC_OPTIONS', '')} -no_signal_handler".strip()

if __name__ != "pinbore.fem":   # one module, one name: never a second copy as `fem`
    raise ImportError("fem/ is the package pinbore.fem: import pinbore.fem")
