"""`pinbore report`: one self-contained HTML page (images inline) from the results in build/.

Each stage contributes a section, a function of what that stage wrote under build/ (and the
benchmarks under bench/); a section whose results are absent says so. The page is a pure
function of the files it reads: built again from the same files it is the same.
"""

from pathlib import Path

from pinbore.calibration import report as calibration_report
from pinbore.core.html import STYLE
from pinbore.core.output import write_text_atomic
from pinbore.fem import report as fem_report
from pinbore.reduced import report as reduced_report


def build(build_dir, out) -> Path:
    build_dir = Path(build_dir)
    bench = Path("bench")
    sections = [fem_report.section(build_dir, bench), calibration_report.section(build_dir, bench),
                reduced_report.section(build_dir), reduced_report.dynamics_section(build_dir)]
    page = ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            f"<title>pinbore report</title><style>{STYLE}</style></head><body>"
            "<h1>pinbore: contact in pin-in-bore (revolute clearance) joints</h1>"
            "<p>Finite-element contact of a pin in a bore (DOLFINx), calibration of the contact "
            "laws and reduced multibody models. Units SI; 2D forces are per unit length "
            "(N/m).</p>" + "".join(sections) + "</body></html>\n")
    index = Path(out) / "index.html"
    write_text_atomic(index, page)
    return index
