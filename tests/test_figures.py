"""Every picture pinbore writes is the same byte for byte when drawn again from the same data:
no metadata that changes between runs (matplotlib's or VTK's Software entry, times)."""

import numpy as np
from conftest import ROOT, pinbore

from pinbore.core.figures import plt, save_image, save_png


def chunks(png: bytes) -> list[bytes]:
    """The chunk types of a PNG file, in order."""
    found, at = [], 8
    while at < len(png):
        length = int.from_bytes(png[at:at + 4], "big")
        found.append(png[at + 4:at + 8])
        at += 12 + length
    return found


def test_a_figure_saved_twice_is_the_same_and_carries_no_text(tmp_path):
    paths = []
    for k in range(2):
        fig, ax = plt.subplots()
        ax.plot(np.linspace(0, 1, 50) ** 2)
        save_png(fig, tmp_path / f"{k}.png", layout=True)
        paths.append(tmp_path / f"{k}.png")
    data = [p.read_bytes() for p in paths]
    assert data[0] == data[1]
    assert not {b"tEXt", b"iTXt", b"zTXt", b"tIME"} & set(chunks(data[0]))


def test_a_pixel_array_is_written_without_metadata(tmp_path):
    pixels = (np.arange(48).reshape(4, 4, 3) * 5).astype(np.uint8)
    save_image(pixels, tmp_path / "a.png")
    assert not {b"tEXt", b"iTXt", b"zTXt", b"tIME"} & set(chunks((tmp_path / "a.png").read_bytes()))


def test_mesh_previews_are_reproducible(tmp_path):
    """The 2D preview (matplotlib) of a shipped scene, drawn twice by the command."""
    scene = ROOT / "scenes" / "fem" / "steel_c100um.toml"
    for k in range(2):
        assert pinbore("mesh", scene, "--out", tmp_path / f"m{k}").returncode == 0
    assert (tmp_path / "m0" / "preview.png").read_bytes() == (tmp_path / "m1" / "preview.png").read_bytes()
