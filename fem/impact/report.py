"""The report's section on the dynamic impacts (build/impact/): each run's restitution,
contact duration, peak force and energy book, read through the impact files' module (its
summary and its history, both checked)."""

import html
from pathlib import Path

from pinbore.core.html import note, table
from pinbore.fem.impact import file as impact_file


def section(build_dir: Path, bench: Path) -> str:
    runs = sorted((build_dir / "impact").glob(f"*/{impact_file.SUMMARY}"))
    parts = ["<h2>Dynamic impacts of the pin in its bore</h2>",
             "<p>The pin flies into its bore and rebounds (plane strain, per unit length; "
             "<code>pinbore impact</code>): the restitution e = rebound / impact speed, the "
             "contact duration, the peak force and the largest residual of the energy book.</p>"]
    if not runs:
        return "".join(parts) + note("No impacts under build/impact (run make impact).")
    rows = []
    for path in runs:
        s = impact_file.read_summary(path)
        history = impact_file.read_history(impact_file.history_beside(path))
        rows.append([html.escape(path.parent.name), f"{s.speed_m_per_s:g}",
                     "—" if s.restitution is None else f"{s.restitution:.4f}",
                     "—" if s.contact_duration_s is None else f"{s.contact_duration_s * 1e6:.4g}",
                     f"{s.peak_force_N_per_m:.4g}", f"{s.energy.max_relative_residual:.1e}",
                     f"{history.time.size}", s.status])
    parts.append(table(["run", "speed (m/s)", "e", "contact (us)", "peak force (N/m)",
                        "energy book residual / E0", "time points", "status"], rows))
    return "".join(parts)
