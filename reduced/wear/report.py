"""The report's section on wear: per worn joint, what its surfaces lost after its cycles and
where, beside the picture of the worn depths and the worn bore and pin."""

import html
from pathlib import Path

from pinbore.core.html import figure, note, png_data, table
from pinbore.reduced.wear import summary as wear_summary


def section(build_dir: Path, bench: Path) -> str:
    runs = sorted((build_dir / "wear").glob(f"*/{wear_summary.SUMMARY}"))
    parts = ["<h2>Wear of the clearance joints</h2>",
             "<p>Archard's law on the contact pressure of the joint's FE run under the joint's "
             "force over the mechanism's last forcing period, times the cycles "
             "(<code>pinbore wear</code>; one-way: the new joint's pressure and motion; "
             "docs/theory/wear.md).</p>"]
    if not runs:
        return "".join(parts) + note("No worn joints under build/wear (run make wear).")
    rows = []
    for path in runs:
        s = wear_summary.read(path)
        rows.append([path.parent.name, s.joint, f"{s.cycles:.3g}",
                     f"{s.sliding_distance_in_contact_per_cycle_m * 1e3:.3g}",
                     f"{s.peak_force_per_length_N_per_m:.4g}" + (" (extrapolated)" if s.extrapolated else ""),
                     f"{s.bore.volume_m3 * 1e9:.4g}", f"{s.bore.max_depth_m * 1e6:.4g} at {s.bore.at_deg:.0f}",
                     f"{s.pin.volume_m3 * 1e9:.4g}", f"{s.pin.max_depth_m * 1e6:.4g} at {s.pin.at_deg:.0f}"])
    parts.append(table(["scene", "joint", "cycles", "slid in contact per cycle (mm)",
                        "peak load (N/m)", "bore: volume (mm^3)", "bore: deepest (um at deg)",
                        "pin: volume (mm^3)", "pin: deepest (um at deg)"], rows))
    for path in runs:
        picture = path.parent / "wear.png"
        if picture.exists():
            parts.append(figure(png_data(picture), f"{html.escape(path.parent.name)}: the worn "
                                "depths against angle, and the worn bore and pin (depth exaggerated)"))
    return "".join(parts)
