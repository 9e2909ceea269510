"""Pieces of the report page: PNGs inline as base64, figures with captions, tables.

A stage's report section (`pinbore.<stage>.report.section`) builds its HTML from these and
from what the stage wrote under build/; the page itself is put together by `pinbore.report`.
"""

import base64
import csv
import html
import io
from pathlib import Path

STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1100px; margin: 2em auto; color: #222;
       line-height: 1.45; padding: 0 1em; }
h1 { border-bottom: 2px solid #446; } h2 { margin-top: 2em; border-bottom: 1px solid #aaa; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.92em; color: #444; }
table { border-collapse: collapse; font-size: 0.9em; margin: 1em 0; display: block;
        max-width: 100%; overflow-x: auto; }
td, th { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th { background: #eef; } td:first-child, th:first-child { text-align: left; }
.note { background: #f6f6f0; border-left: 4px solid #cc8; padding: 0.5em 1em; }
pre, code { overflow-wrap: anywhere; } pre { white-space: pre-wrap; }
details > summary { cursor: pointer; } details > summary h2 { display: inline-block; margin: 1em 0 0; }
.answers { background: #f3f6fb; border: 1px solid #ccd; padding: 0 1em; }
.answers h2 { margin-top: 0.5em; } .answers th { background: none; text-align: left; }
.answers td { text-align: left; } nav ol { columns: 2; }
"""


PNG_START, PNG_END = b"\x89PNG\r\n\x1a\n", b"IEND\xaeB`\x82"   # the signature and the IEND chunk


def png_data(path: Path) -> str:
    """A PNG file as base64; ValueError for a file that is not a whole PNG (truncated, or
    text), which the page would show as a broken image."""
    data = Path(path).read_bytes()
    if not (data.startswith(PNG_START) and data.endswith(PNG_END)):
        raise ValueError(f"{path}: not a whole PNG image")
    return base64.b64encode(data).decode()


def figure_data(fig) -> str:
    """A matplotlib figure as base64 PNG (through save_png: no metadata; closed)."""
    from pinbore.core.figures import save_png   # noqa: PLC0415 (the page's style loads no matplotlib)

    buffer = io.BytesIO()
    save_png(fig, buffer, dpi=100)
    return base64.b64encode(buffer.getvalue()).decode()


def figure(data: str, caption: str) -> str:
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(caption)}">'
            f"<figcaption>{caption}</figcaption></figure>")


def note(text: str) -> str:
    """A highlighted remark (HTML already escaped by the caller)."""
    return f"<p class='note'>{text}</p>"


def table(header: list[str], rows: list[list]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def outcome_counts(path: Path, outcomes: list[str]) -> str:
    """A table of a stress CSV (bench/stress_*.csv, columns sweep, outcome, ok): per sweep,
    how many points ended in each outcome, and how many failed the criterion."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    sweeps = list(dict.fromkeys(row["sweep"] for row in rows))
    body = [[sweep] + [sum(r["sweep"] == sweep and r["outcome"] == o for r in rows) or ""
                       for o in outcomes]
            + [sum(r["sweep"] == sweep and r["ok"] != "True" for r in rows) or ""]
            for sweep in sweeps]
    body.append(["all"] + [sum(r["outcome"] == o for r in rows) for o in outcomes]
                + [sum(r["ok"] != "True" for r in rows)])
    return table(["sweep"] + outcomes + ["failed the criterion"], body)
