"""pinbore: finite-element contact study of pin-in-bore (revolute clearance) joints.

One import package whose floors keep their folders at the top of the repository (a
package-directory mapping in pyproject.toml). Data flows one way, and a floor imports only
from the floors below it:

    pinbore.core         core/          errors, scene files, atomic outputs, figures, report pieces
    pinbore.laws         laws/          the contact, damping and friction laws
    pinbore.meshes       meshes/        Gmsh models of the pin in its bore
    pinbore.fem          fem/           DOLFINx contact: load-approach curves, pressures
    pinbore.calibration  calibration/   law fits and ranking on the FE curves: laws.json
    pinbore.reduced      reduced/       multibody models with clearance joints, nonlinear dynamics
    pinbore.cli, pinbore.report  pinbore/   the roof: the `pinbore` command and the HTML report
"""
