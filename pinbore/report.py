"""`pinbore report`: one self-contained HTML page (images inline) from the results in build/.

Each stage contributes its sections (pinbore.stages: Stage.sections), each a function of what
that stage wrote under build/ (and the benchmarks under bench/); a section whose results are
absent says so. The page is a pure
function of the files it reads: built again from the same files it is the same.
"""

import html
import re
import sys
from pathlib import Path

from pinbore import stages
from pinbore.core.errors import InputError
from pinbore.core.html import STYLE
from pinbore.core.output import atomic_directory

# each section's and answer's module is imported when the page is built (a bad --build
# answers before any loads)
HEADING = re.compile(r"^<h2>(.*?)</h2>", re.S)


def folded(index: int, heading: str, content: str) -> tuple[str, str]:
    """(the section as a <details> block that folds, open, under its own heading, with an
    anchor; its entry in the table of contents)."""
    match = HEADING.match(content)
    title = match.group(1) if match else html.escape(heading)
    body = content[match.end():] if match else content
    anchor = f"section-{index}"
    return (f"<details open id='{anchor}'><summary><h2>{title}</h2></summary>{body}</details>",
            f"<li><a href='#{anchor}'>{title}</a></li>")


def answers_box(build_dir: Path) -> str:
    """The first screen: what the results answer, each with its number (a stage without
    results says nothing here)."""
    rows = []
    for function in stages.answers():
        try:
            rows += stages.resolve(function)(build_dir)
        except Exception:   # noqa: BLE001 (its section, reading the same files, says why)
            rows.append((html.escape(function.partition(":")[0].split(".")[1]), "not available: its files do not "
                         "read (see its section)"))
    if not rows:
        return "<p class='note'>No results to answer from yet: run <code>make</code>.</p>"
    items = "".join(f"<tr><th>{q}</th><td>{a}</td></tr>" for q, a in rows)
    return f"<section class='answers'><h2>Answers</h2><table>{items}</table></section>"


def command(args) -> int:
    """`pinbore report` on its parsed arguments (pinbore.stages): 1 when a section was left out."""
    _, problems = build(args.build, args.out)
    for line in problems:
        print(f"pinbore report: {line}", file=sys.stderr)
    return 1 if problems else 0


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
    sections, contents, problems = [], [], []
    for index, section in enumerate(stages.sections()):
        heading = section.heading
        try:
            content = stages.resolve(section.function)(build_dir, bench)
        except Exception as err:   # noqa: BLE001 (a section fails alone, whatever broke it)
            why = str(err) if isinstance(err, InputError) else (
                f"its files do not read as expected ({type(err).__name__}: {err})")
            problems.append(f"{heading} section left out: {why}")
            content = (f"<h2>{html.escape(heading)}</h2><p class='note'>Not built: "
                       f"{html.escape(why)}</p>")
        block, entry = folded(index, heading, content)
        sections.append(block)
        contents.append(entry)
    page = ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>pinbore report</title><style>{STYLE}</style></head><body>"
            "<h1>pinbore: contact in pin-in-bore (revolute clearance) joints</h1>"
            "<p>Finite-element contact of a pin in a bore (DOLFINx), calibration of the contact "
            "laws and reduced multibody models. Units SI; 2D forces are per unit length "
            "(N/m).</p>" + answers_box(build_dir)
            + f"<nav><h2>Contents</h2><ol>{''.join(contents)}</ol></nav>"
            + "".join(sections) + "</body></html>\n")
    with atomic_directory(out) as tmp:
        (tmp / "index.html").write_text(page, encoding="utf-8")
    return Path(out) / "index.html", problems
