"""pinbore: finite-element contact study of pin-in-bore (revolute clearance) joints.

One import package whose floors keep their folders at the top of the repository (a
package mapping in pyproject.toml; the compiled core, pinbore.core.cpp, is cpp/). Data flows one way, and a floor imports only
from the floors below it:

    pinbore.core         core/          errors, scene files, atomic outputs, figures, report
                                        pieces, the parallel runner, statistics; the compiled
                                        core (cpp/)
    pinbore.laws         laws/          the contact, damping, friction and wear laws; laws.json
    pinbore.meshes       meshes/        Gmsh models of the pin in its bore and of flexible bodies
    pinbore.fem          fem/           DOLFINx: contact curves and pressures, impacts, modes
    pinbore.calibration  calibration/   law fits and ranking on the FE curves: laws.json
    pinbore.reduced      reduced/       mechanisms with clearance joints, their nonlinear
                                        dynamics, the wear of a joint
    pinbore (the roof)   pinbore/       the registry of stages that the rest reads, the
                                        `pinbore` command, the Python API (`pinbore.run`),
                                        studies, the report, the laws' export
"""

# An editable install (scikit-build-core's redirect) also lists the repository's root among
# this package's folders, the parent of the floors' folders it maps: a root-level folder
# (bench/, tests/) would then import as pinbore.<folder>. The root, the folder above this
# file's, is dropped by identity (a clone is often itself named pinbore); the floors are
# found by their own mapping.
import os as _os   # noqa: E402

_ROOT = _os.path.dirname(_os.path.dirname(_os.path.abspath(__file__)))
__path__[:] = [p for p in __path__ if _os.path.abspath(p) != _ROOT]   # noqa: F821

API = ("scene", "run", "calibrate")   # pinbore.api: scenes and stages in process
FLOORS = ("core", "laws", "meshes", "fem", "calibration", "reduced")


def __getattr__(name):
    """`pinbore.run(...)`, `pinbore.laws.load(...)`, `pinbore.__version__`: loaded on first use,
    so that importing a floor (every floor is a subpackage of this one) loads none of them."""
    import importlib   # noqa: PLC0415

    if name in API:
        return getattr(importlib.import_module("pinbore.api"), name)
    if name in FLOORS:
        return importlib.import_module(f"pinbore.{name}")
    if name == "__version__":
        from pinbore.cli import version   # noqa: PLC0415

        return version()
    raise AttributeError(f"module 'pinbore' has no attribute {name!r}")
