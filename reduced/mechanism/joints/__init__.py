"""The clearance joints of a mechanism: what every type shares (contact.py: its contact laws
and materials)."""
