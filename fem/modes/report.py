"""The report's section on the flexible bodies: each reduced body's free modes beside the
whole FE model's (the reduction's error), its mass and the time the reduction took, and the
pictures of its mode shapes."""

import html
from pathlib import Path

from pinbore.core.html import figure, note, png_data, table
from pinbore.fem.modes import file as body_file


def section(build_dir: Path, bench: Path) -> str:
    runs = sorted((build_dir / "modes").glob(f"*/{body_file.SUMMARY}"))
    parts = ["<h2>Flexible bodies: modes from the FE</h2>",
             "<p>Each body's FE model (Gmsh, DOLFINx) reduced by Craig-Bampton with its joint "
             "interfaces tied rigidly to their frames, then to the reduced body's own free modes "
             "in the mean-axis frame (<code>pinbore modes</code>). The whole model's free modes "
             "(the interfaces tied alike) measure the truncation.</p>"]
    if not runs:
        return "".join(parts) + note("No reduced bodies under build/modes (run make modes).")
    for path in runs:
        s = body_file.read_summary(path)
        name = path.parent.name
        rows = []
        for k, f in enumerate(s.frequencies_Hz):
            full = s.full_frequencies_Hz[k] if k < len(s.full_frequencies_Hz) else None
            error = s.reduction_error[k] if k < len(s.reduction_error) else None
            rows.append([k + 1, f"{f:.5g}", "" if full is None else f"{full:.5g}",
                         "" if error is None else f"{error:.1e}"])
        parts.append(f"<h3>{html.escape(name)}</h3>")
        parts.append(f"<p>{s.dofs} dofs, mass {s.mass_kg:.4g} kg; first held-interface "
                     f"frequency {s.fixed_interface_frequencies_Hz[0]:.4g} Hz; reduced in "
                     f"{s.wall_time_s['total']:.1f} s; mean-axis residual "
                     f"{s.mean_axis_residual:.1e}.</p>")
        parts.append(table(["mode", "reduced body (Hz)", "whole FE model (Hz)",
                            "reduced / whole - 1"], rows))
        picture = path.parent / "mode_shapes.png"
        if picture.exists():
            parts.append(figure(png_data(picture), f"{name}: the first free modes of the "
                                "reduced body, deformed over the undeformed body"))
    return "".join(parts)
