"""`pinbore report`: one self-contained HTML page (images inline) from the results in build/.

Each stage contributes a section; a section whose results are absent says so. The page is
a pure function of the files it reads: built again from the same files it is the same.
"""

import base64
import html
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from pinbore.output import write_text_atomic  # noqa: E402

STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1100px; margin: 2em auto; color: #222;
       line-height: 1.45; padding: 0 1em; }
h1 { border-bottom: 2px solid #446; } h2 { margin-top: 2em; border-bottom: 1px solid #aaa; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.92em; color: #444; }
table { border-collapse: collapse; font-size: 0.9em; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th { background: #eef; } td:first-child, th:first-child { text-align: left; }
.note { background: #f6f6f0; border-left: 4px solid #cc8; padding: 0.5em 1em; }
"""


def png_data(path: Path) -> str:
    return base64.b64encode(Path(path).read_bytes()).decode()


def figure_data(fig) -> str:
    """A matplotlib figure as base64 PNG, without metadata that would change between runs."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, metadata={"Software": None})
    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode()


def figure(data: str, caption: str) -> str:
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(caption)}">'
            f"<figcaption>{caption}</figcaption></figure>")


def table(header: list[str], rows: list[list]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def build(build_dir, out) -> Path:
    from calibration import report as calibration_report
    from fem import report as fem_report
    from reduced import report as reduced_report

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
