"""Wear of a clearance joint: Archard's law on the FE contact pressure under the joint force
history of a mechanism's cycle (the bore's and the pin's worn depth against angle)."""
