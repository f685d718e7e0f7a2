"""What the rungs' report_plots.py share: saving a figure for the ladder
report (ci/report loads each rung's report_plots.py and lists the images
its plots() returns)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def save_figure(fig, out_dir, name: str, caption: str, dpi: int = 110) -> tuple:
    """Write `fig` as out_dir/name, close it and return the report's
    (caption, png name) entry."""
    fig.savefig(Path(out_dir) / name, dpi=dpi)
    plt.close(fig)
    return (caption, name)


def particle_panels(snapshots: list, field: str, title, colour_label: str, panel=(3.0, 2.6), **scatter):
    """A row of 2-D particle snapshots (dicts with "x", "y" and `field`), one
    panel each, the particles coloured by `field` (scatter's keywords: s,
    cmap, vmin, vmax), titled title(snapshot), equal aspect, no ticks, one
    colour bar labelled `colour_label`. Returns the figure."""
    fig, axes = plt.subplots(1, len(snapshots), figsize=(panel[0] * len(snapshots), panel[1]), squeeze=False)
    for ax, snap in zip(axes[0], snapshots):
        sc = ax.scatter(snap["x"], snap["y"], c=snap[field], **scatter)
        ax.set_title(title(snap), fontsize=9)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(sc, ax=axes[0].tolist(), shrink=0.8, label=colour_label)
    return fig
