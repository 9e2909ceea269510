"""The demos (demos/demo_*.py) run top to bottom, at a reduced size, as a reader runs them.
Each demo asserts its own physics against an independent reference (a closed form, a
conservation law); here each runs in the test's process with PINBORE_DEMO_SMALL=1, its files
under the test's folder. Every demo is a page of the docs (docs/_ext/demo_pages.py reads the
scripts through docs/demos, a link to demos/), listed in the docs' index."""

import re
import runpy
import sys

import pytest
from conftest import ROOT

DEMOS = sorted((ROOT / "demos").glob("demo_*.py"))


@pytest.mark.parametrize("path", DEMOS, ids=lambda path: path.stem)
def test_demo_runs_and_its_checks_hold(path, tmp_path, monkeypatch):
    monkeypatch.setenv("PINBORE_DEMO_SMALL", "1")
    monkeypatch.setenv("PINBORE_DEMO_OUT", str(tmp_path))
    runpy.run_path(str(path), run_name="__main__")


def test_every_demo_is_a_page_of_the_docs():
    assert len(DEMOS) >= 5
    assert (ROOT / "docs" / "demos").resolve() == (ROOT / "demos").resolve()
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    assert set(re.findall(r"^demos/(demo_\w+)$", index, re.MULTILINE)) == {p.stem for p in DEMOS}
    assert "(demos/)" in (ROOT / "README.md").read_text(encoding="utf-8")


def test_the_readmes_python_is_a_demos():
    """The README's Python section opens with lines of a demo, as the demo has them."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index("\n## Python\n"):]
    demo = re.search(r"\((demos/demo_\w+\.py)\)", section)[1]
    block = section[section.index("```python\n") + 10:section.index("\n```\n")]
    lines = {line.strip() for line in (ROOT / demo).read_text(encoding="utf-8").splitlines()}
    shown = [line.strip() for line in block.splitlines() if line.strip()]
    assert len(shown) >= 8 and set(shown) <= lines, set(shown) - lines


def test_a_demo_page_is_its_cells_line_for_line():
    """Text cells lose their `# `, code cells become Python code blocks, each line of the page
    at its line in the script; a text line without `# ` is an error naming the line."""
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    import demo_pages

    script = "# %% [markdown]\n# # Title\n#\n# Text.\n\n# %%\nx = 1\n\n# %% [markdown]\n# More.\n"
    page = demo_pages.markdown(script).splitlines()
    assert page[1:4] == ["# Title", "", "Text."]
    assert page[5:8] == ["```python", "x = 1", "```"]
    assert page[9] == "More."
    linked = demo_pages.markdown("# %% [markdown]\n# [a](demo_push.py), [b](../docs/study.md), "
                                 "[c](https://x.org)\n", str(ROOT / "demos" / "x.py"), ROOT / "docs")
    assert linked.splitlines()[1] == "{doc}`a </demos/demo_push>`, {doc}`b </study>`, [c](https://x.org)"
    with pytest.raises(ValueError, match="demo:3: a line of a markdown cell"):
        demo_pages.markdown("# %% [markdown]\n# Title\nnot a comment\n")
