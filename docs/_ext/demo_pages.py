"""The demos as pages: each script of demos/ (docs/demos links to that folder) is a page of the
documentation, read by the parser below.

A demo is a Python script in the percent format that Jupytext, VS Code and Spyder read as
cells: a line `# %% [markdown]` opens a text cell, whose lines are Markdown behind `# `; a
line `# %%` opens a code cell. The page is the text cells as Markdown (MyST, as every page of
these docs) and the code cells as Python code blocks, in the script's order; lines before the
first cell marker are code. The page's lines keep the numbers they have in the script (a code
cell's closing fence may push the next cell down a line), so a warning points at the script.

A text cell links other demos and the docs' pages as files, relative to demos/ (as a reader
of the repository follows them): `[the calibration](demo_calibration.py)`,
`[contact](../docs/theory/contact.md)`. Sphinx would resolve such a path through the link
docs/demos, out of the docs' folder; the page has them as references to the pages instead.
"""

from __future__ import annotations

import re
from pathlib import Path

MARKER = re.compile(r"^# %%(?P<rest>.*)$")
LINK = re.compile(r"\[(?P<text>[^\]`<>]+)\]\((?P<target>[^)\s#:]+)\)")


def cells(text: str) -> list[tuple[str, int, list[str]]]:
    """(kind, first line's number (1-based), lines) of each cell, kind "markdown" or "code"."""
    found = [["code", 1, []]]
    for number, line in enumerate(text.splitlines(), 1):
        marker = MARKER.match(line)
        if marker:
            kind = "markdown" if marker["rest"].strip().startswith("[markdown]") else "code"
            found.append([kind, number + 1, []])
        else:
            found[-1][2].append(line)
    return [(kind, start, lines) for kind, start, lines in found if any(line.strip() for line in lines)]


def uncommented(line: str, where: str) -> str:
    """A text cell's line without its `# ` (a bare `#` is an empty line)."""
    if line.strip() == "" or line == "#":
        return ""
    if not line.startswith("# "):
        raise ValueError(f"{where}: a line of a markdown cell must start with '# ': {line!r}")
    return line[2:]


def page_links(line: str, folder: Path, docs: Path) -> str:
    """The links of a text line to a demo of `folder` or to a page under `docs` as {doc}
    references to those pages (other links as they are)."""
    def reference(link: re.Match) -> str:
        path = (folder / link["target"]).resolve()
        if path.suffix == ".py" and path.parent == folder.resolve():
            return f"{{doc}}`{link['text']} </demos/{path.stem}>`"
        if path.suffix == ".md" and path.is_relative_to(docs.resolve()):
            return f"{{doc}}`{link['text']} </{path.relative_to(docs.resolve()).with_suffix('').as_posix()}>`"
        return link[0]
    return LINK.sub(reference, line)


def markdown(text: str, source: str = "demo", docs: Path | None = None) -> str:
    """The page of a demo script: Markdown whose line n is the script's line n, or near it (a
    code cell's closing fence takes a line of its own). With `docs` (the docs' folder), the
    links to demos and pages are references (`page_links`)."""
    folder = Path(source).resolve().parent
    out: list[str] = []
    for kind, start, lines in cells(text):
        body = ([uncommented(line, f"{source}:{start + k}") for k, line in enumerate(lines)]
                if kind == "markdown" else list(lines))
        if kind == "markdown" and docs is not None:
            body = [page_links(line, folder, docs) for line in body]
        while body and not body[0].strip():
            body.pop(0)
            start += 1
        while body and not body[-1].strip():
            body.pop()
        out.extend([""] * (start - 2 - len(out)))   # up to the line before the cell's first
        out.extend(["```python", *body, "```"] if kind == "code" else ["", *body])
    return "\n".join(out) + "\n"


def setup(app):
    from myst_parser.parsers.sphinx_ import MystParser

    class DemoParser(MystParser):
        """A demo script read as its Markdown page (`markdown`)."""

        supported = ("demo",)

        def parse(self, inputstring: str, document) -> None:
            super().parse(markdown(inputstring, document["source"], Path(app.srcdir)), document)

    app.add_source_suffix(".py", "demo")
    app.add_source_parser(DemoParser)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
