"""pinbore: finite-element contact study of pin-in-bore (revolute clearance) joints.

This package is the shell around the stages: scene files, input errors, atomic outputs,
the command line and the report. The stages are top-level packages and data flows
meshes -> fem -> calibration -> reduced; each imports only from stages upstream of it
and from the shared modules here (`errors`, `scene`, `output`).
"""
