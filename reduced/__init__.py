"""Stage 4: planar multibody models with revolute clearance joints (issue 6)."""
