"""Multibody models with clearance joints, three rooms: `mechanism/`, planar and spatial
mechanisms of rigid and flexible bodies with revolute, cylindrical, spherical and
translational clearance joints, run by the compiled core's engine (`pinbore reduced`);
`dynamics/`, their nonlinear dynamics: Poincare maps, bifurcations, continuation, design maps
(`pinbore dynamics`); `wear/`, the wear of a clearance joint by Archard's law on its FE
pressure (`pinbore wear`); and the report's sections (`report`)."""

if __name__ != "pinbore.reduced":   # one module, one name: never a second copy as `reduced`
    raise ImportError("reduced/ is the package pinbore.reduced: import pinbore.reduced")
