"""The clearance joints of a mechanism, one type a module, and their registry: every user
of a clearance joint (the scene's rules, the model's build, the outputs, the flows) asks its
type here (`of`) and never branches on the type's name.

A type's module holds its scene model (pydantic, validated before any model is built; the
spatial table of the cylindrical and spherical joints is one, journal.py) and its subclass
of base.Clearance: the ideal joint that closes it, its contacts and its law's table, how
deep the table reaches, its contacts' roles, its output columns, the directions across it.
What the types share: contact.py (the contact laws and materials of a scene table), bore.py
(a pin in its bore). A new type is its module and one line below.
"""

from pinbore.reduced.mechanism.joints import cylindrical, revolute, spherical, translational

TYPES = {
    "revolute": revolute.RevoluteClearance,
    "cylindrical": cylindrical.CylindricalClearance,
    "spherical": spherical.SphericalClearance,
    "translational": translational.TranslationalClearance,
}


def of(c):
    """The clearance joint c (its scene model) as its type's base.Clearance."""
    return TYPES[c.type](c)
