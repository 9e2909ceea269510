"""The report page: its first screen answers from the results (a calibrated mechanism beside
its twin on the published law), a table of contents whose links reach sections that fold,
and no sideways overflow in a real browser (headless Chromium, where installed)."""

import re
import shutil
import subprocess
import tomllib

import pytest
import tomli_w
from conftest import ROOT, pinbore
from test_calibration import calibrated_scene, synthetic_laws_file

from pinbore.reduced.mechanism import summary

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """A report of two short runs of the Flores slider-crank: on Hertz's law and on a law
    calibrated on a synthetic curve (build/reduced/flores, flores_calibrated)."""
    tmp = tmp_path_factory.mktemp("report")
    build = tmp / "build"
    published = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    calibrated = calibrated_scene(synthetic_laws_file(tmp))
    for name, data in (("flores", published), ("flores_calibrated", calibrated)):
        (tmp / f"{name}.toml").write_text(tomli_w.dumps(data | {"duration": 0.003}))
        done = pinbore("reduced", tmp / f"{name}.toml", "--out", build / "reduced" / name)
        assert done.returncode == 0, done.stderr
    done = pinbore("report", "--build", build, "--out", tmp / "report")
    assert done.returncode == 0, done.stderr
    return tmp / "report" / "index.html", build


def test_the_first_screen_answers_from_the_runs(page):
    path, build = page
    text = path.read_text()
    answers = text[text.index("<section class='answers'>"):text.index("</section>")]
    peaks = [summary.read(build / "reduced" / n / "summary.json").peak_normal_force_N / 1e3
             for n in ("flores_calibrated", "flores")]
    assert "Peak joint force, flores" in answers
    assert f"{peaks[0]:.3g} kN on the calibrated law, {peaks[1]:.3g} kN on the published" in answers
    assert text.index("<section class='answers'>") < text.index("<details")


def test_the_contents_reach_every_section_which_folds(page):
    text = page[0].read_text()
    links = re.findall(r"<li><a href='#(section-\d+)'>", text)
    folds = re.findall(r"<details open id='(section-\d+)'><summary><h2>", text)
    assert links == folds and len(folds) == 8


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium on this machine")
@pytest.mark.parametrize("width", [1280, 800])
def test_no_sideways_overflow_in_a_browser(page, tmp_path, width):
    """The page's scroll width equals the window's: tables scroll inside themselves, images
    shrink (measured in Chromium: the page before this layout overflowed by 642 px at
    1280 px)."""
    probe = ("<script>addEventListener('load', () => document.body.setAttribute('data-overflow', "
             "String(document.documentElement.scrollWidth - document.documentElement.clientWidth)))"
             "</script></body>")
    copy = tmp_path / "probe.html"
    copy.write_text(page[0].read_text().replace("</body>", probe))
    dom = subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
                          f"--window-size={width},900", "--virtual-time-budget=5000", "--dump-dom",
                          copy.as_uri()], capture_output=True, text=True, timeout=120).stdout
    assert re.search(r'data-overflow="(-?\d+)"', dom).group(1) == "0"
