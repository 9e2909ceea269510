"""Pictures that are the same byte for byte when drawn again from the same data.

Every PNG that pinbore writes goes through `save_png` (matplotlib figures) or `save_image`
(pixel arrays, e.g. off-screen pyvista renderings): no metadata that changes between runs or
versions (matplotlib's Software entry, VTK's), fixed resolution.
"""

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

__all__ = ["plt", "save_png", "save_image", "offscreen_pyvista"]


def save_png(fig, path, dpi: int = 110, layout: bool = False, **savefig) -> None:
    """Write a matplotlib figure as PNG without metadata, then close it. `layout` applies
    tight_layout first; other keywords go to savefig (e.g. bbox_inches)."""
    if layout:
        fig.tight_layout()
    fig.savefig(path, format="png", dpi=dpi, metadata={"Software": None}, **savefig)
    plt.close(fig)


def save_image(pixels: np.ndarray, path) -> None:
    """Write an (h, w, 3 or 4) uint8 array as PNG, with no metadata chunks."""
    Image.fromarray(np.ascontiguousarray(pixels)).save(path, format="PNG")


def offscreen_pyvista():
    """pyvista for off-screen pictures. Without an X display VTK's default window warns and
    falls back; EGL renders head-less, so it is chosen unless the user set a window."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista

    return pyvista
