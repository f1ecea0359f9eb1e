"""The matplotlib figure: panels side by side under their titles, the deviation mode's colour
bar and legend, drawn by Agg's Gouraud triangles and written as a PNG of exactly the requested
size (atomically)."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..io.atomic import atomic_path
from .checks import _matplotlib
from .deviation import EXACT_G1_DEG, _AngleScale
from .panel import _Panel

_DPI = 100
_BACKGROUND = (1.0, 1.0, 1.0)


def _draw(
    path: Path,
    panels: Sequence[_Panel],
    size: tuple[int, int],
    scale: _AngleScale | None = None,
    colorbar_label: str = "",
    legend: Sequence[tuple[str, NDArray[np.float64]]] = (),
) -> None:
    """Lay the panels out side by side (with a colour bar at the right when ``scale``, and the
    ``legend`` entries (label, colour) in a band of their own below) and write the PNG."""
    Figure = _matplotlib()

    width, height = size
    figure = Figure(figsize=(width / _DPI, height / _DPI), dpi=_DPI, facecolor=_BACKGROUND)
    bar_width = 0.0 if scale is None else min(0.22, 120.0 / width)
    panel_width = (1.0 - bar_width) / len(panels)
    title_size = float(np.clip(min(height, width * panel_width) / 30.0, 6.0, 15.0))
    # a glyph is about 0.6 of the font size wide: the font shrinks (to 6 pt) until the longest
    # line fits its panel, and lines still too long are wrapped
    longest = max(
        (len(line) for p in panels if p.title for line in p.title.splitlines()), default=0
    )
    if longest:
        title_size = max(
            6.0, min(title_size, 0.95 * width * panel_width / (0.6 * longest) * 72.0 / _DPI)
        )
    fits = max(8, int(0.95 * width * panel_width / (0.6 * title_size * _DPI / 72.0)))
    titles = [
        "\n".join(textwrap.fill(line, fits) for line in p.title.splitlines()) if p.title else None
        for p in panels
    ]
    lines = max((t.count("\n") + 1 for t in titles if t), default=0)
    title_band = (
        min(0.4, (0.9 + 1.3 * lines) * title_size * (_DPI / 72.0) / height) if lines else 0.0
    )
    legend_size = max(6.0, title_size * 0.8)
    legend_band = min(0.2, 2.2 * legend_size * (_DPI / 72.0) / height) if legend else 0.0
    for column, panel in enumerate(panels):
        axes = figure.add_axes(
            (column * panel_width, legend_band, panel_width, 1.0 - title_band - legend_band)
        )
        axes.set_axis_off()
        box_w, box_h = width * panel_width, height * (1.0 - title_band - legend_band)
        units_per_pixel = max(panel.extent[0] / box_w, panel.extent[1] / box_h)
        half = units_per_pixel * np.array([box_w, box_h]) / 2.0
        low, high = panel.centre - half, panel.centre + half
        axes.set_xlim(low[0], high[0])
        axes.set_ylim(low[1], high[1])
        # triangles wholly outside the picture (zoomed in) are not drawn
        inside = ((panel.polygons.max(axis=1) >= low) & (panel.polygons.min(axis=1) <= high)).all(
            axis=1
        )
        axes.add_artist(_gouraud_artist(panel.polygons[inside], panel.colours[inside]))
        if titles[column]:
            figure.text(
                (column + 0.5) * panel_width,
                1.0 - 0.5 * title_band,
                titles[column],
                ha="center",
                va="center",
                fontsize=title_size,
                color="0.15",
                linespacing=1.3,
            )
    if scale is not None:
        from matplotlib.cm import ScalarMappable

        bar = figure.add_axes((1.0 - 0.95 * bar_width, 0.1, 0.14 * bar_width, 0.8 - title_band))
        colorbar = figure.colorbar(ScalarMappable(norm=scale.norm, cmap=scale.cmap), cax=bar)
        colorbar.set_label(colorbar_label, fontsize=max(6.0, title_size * 0.8))
        bar.tick_params(labelsize=max(6.0, title_size * 0.7))
        if scale.marks_g1 and scale.norm.vmin < EXACT_G1_DEG < scale.norm.vmax:  # "exactly G1"
            bar.axhline(EXACT_G1_DEG, color="white", linewidth=1.2)
            bar.text(
                -0.25,
                EXACT_G1_DEG,
                "exact\nG1",
                transform=bar.get_yaxis_transform(),
                ha="right",
                va="center",
                fontsize=max(5.0, title_size * 0.6),
                color="0.25",
            )
    if legend:
        from matplotlib.patches import Patch

        figure.legend(
            handles=[
                Patch(facecolor=tuple(colour.tolist()), label=text) for text, colour in legend
            ],
            loc="lower left",
            frameon=False,
            fontsize=legend_size,
            ncols=len(legend),
        )
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png", dpi=_DPI, facecolor=_BACKGROUND)


def _gouraud_artist(polygons: NDArray[np.float64], colours: NDArray[np.float64]) -> Any:
    """An artist drawing triangles in the given order (painter's algorithm) with colours
    interpolated linearly from their corners: Agg's Gouraud triangles, one C++ call for all of
    them, without antialiased edges, so neither cracks nor a wireframe show."""
    from matplotlib.artist import Artist

    rgba = np.concatenate([colours, np.ones(colours.shape[:2] + (1,))], axis=-1)

    class GouraudTriangles(Artist):
        def draw(self, renderer: Any) -> None:
            if not self.get_visible() or not len(polygons) or self.axes is None:
                return
            gc = renderer.new_gc()
            gc.set_antialiased(False)
            gc.set_clip_rectangle(self.axes.bbox)  # a zoomed panel stays inside its own box
            renderer.draw_gouraud_triangles(gc, polygons, rgba, self.axes.transData.frozen())
            gc.restore()

    return GouraudTriangles()
