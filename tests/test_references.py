"""The repository speaks for itself: every source a docstring, scene or test cites by key is in
REFERENCES.md and every entry there is cited; no text points at documents a reader of the
repository does not have (a tracker's items, notes kept elsewhere)."""

import re
import subprocess

from conftest import ROOT

KEY = re.compile(r"\[([A-Z][A-Za-z]*\d{4,5}[a-z]?)\]")
# words that point outside the repository; this file names them, so it is not scanned
OUTSIDE = re.compile(r"\bissues?\b|\btickets?\b|the review\b|formula sheet|contact[- ]notes|"
                     r"shared/", re.IGNORECASE)


def tracked(*patterns) -> list:
    files = subprocess.run(["git", "ls-files", *patterns], cwd=ROOT, capture_output=True,
                           text=True, check=True).stdout.split()
    return [ROOT / f for f in files if f != "tests/test_references.py"]


def listed() -> set[str]:
    text = (ROOT / "REFERENCES.md").read_text()
    return set(re.findall(r"^- \*\*\[([^\]]+)\]\*\*", text, re.MULTILINE))


def cited() -> dict[str, set[str]]:
    where = {}
    for path in tracked("*.py", "*.toml", "*.h", "*.cpp", "README.md", "docs/*.md"):   # docs/: every page, nested too
        for key in KEY.findall(path.read_text()):
            where.setdefault(key, set()).add(str(path.relative_to(ROOT)))
    return where


def test_every_cited_key_is_listed():
    unknown = {k: sorted(v) for k, v in cited().items() if k not in listed()}
    assert not unknown, unknown


def test_every_listed_source_is_cited():
    assert not listed() - set(cited())


def test_no_pointers_outside_the_repository():
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in tracked("*.py", "*.toml", "*.md", "Makefile", ".ci/*")
             for n, line in enumerate(path.read_text().splitlines(), 1) if OUTSIDE.search(line)]
    assert not found, "\n".join(found)
