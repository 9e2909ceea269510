"""`pinbore report`: one self-contained HTML page (images inline) from the results in build/.

Each stage contributes a section, a function of what that stage wrote under build/ (and the
benchmarks under bench/); a section whose results are absent says so. The page is a pure
function of the files it reads: built again from the same files it is the same.
"""

import html
from pathlib import Path

from pinbore.calibration import report as calibration_report
from pinbore.core.errors import InputError
from pinbore.core.html import STYLE
from pinbore.core.output import atomic_directory
from pinbore.fem import report as fem_report
from pinbore.fem.impact import report as impact_report
from pinbore.fem.modes import report as modes_report
from pinbore.reduced import report as reduced_report


# (heading, section): each a function of what its stage wrote under build/ (and of bench/)
SECTIONS = [
    ("FE contact", lambda build, bench: fem_report.section(build, bench)),
    ("dynamic impacts", lambda build, bench: impact_report.section(build, bench)),
    ("flexible bodies", lambda build, bench: modes_report.section(build, bench)),
    ("calibration", lambda build, bench: calibration_report.section(build, bench)),
    ("reduced models", lambda build, bench: reduced_report.section(build, bench)),
    ("nonlinear dynamics", lambda build, bench: reduced_report.dynamics_section(build)),
]


def build(build_dir, out) -> tuple[Path, list[str]]:
    """Write OUT/index.html (OUT replaced whole, like every output directory: new, empty or
    pinbore's own, holding no input); (its path, one line per section that could not be
    built).

    A section whose files are missing says so on the page; one whose files do not read (an
    InputError of the stage's seam module: corrupt, truncated, of another version; or any
    other error while reading them) is left out with a note, and the others are built."""
    build_dir = Path(build_dir)
    if not build_dir.is_dir():
        raise InputError(f"--build {build_dir}: not a directory of results (run make first)")
    bench = Path("bench")
    sections, problems = [], []
    for heading, section in SECTIONS:
        try:
            sections.append(section(build_dir, bench))
        except Exception as err:   # noqa: BLE001 (a section fails alone, whatever broke it)
            why = str(err) if isinstance(err, InputError) else (
                f"its files do not read as expected ({type(err).__name__}: {err})")
            problems.append(f"{heading} section left out: {why}")
            sections.append(f"<h2>{html.escape(heading)}</h2><p class='note'>Not built: "
                            f"{html.escape(why)}</p>")
    page = ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            f"<title>pinbore report</title><style>{STYLE}</style></head><body>"
            "<h1>pinbore: contact in pin-in-bore (revolute clearance) joints</h1>"
            "<p>Finite-element contact of a pin in a bore (DOLFINx), calibration of the contact "
            "laws and reduced multibody models. Units SI; 2D forces are per unit length "
            "(N/m).</p>" + "".join(sections) + "</body></html>\n")
    with atomic_directory(out) as tmp:
        (tmp / "index.html").write_text(page, encoding="utf-8")
    return Path(out) / "index.html", problems
