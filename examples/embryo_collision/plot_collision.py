#!/usr/bin/env python3
"""The picture of a rubble collision run: slices through the orbit plane
coloured by material at four or more times, and the bound remnants of the
last snapshot (ci/remnants) as a table.

    python3 examples/embryo_collision/plot_collision.py OUT_DIR [--times 6] [--png FILE]

OUT_DIR is a run's output folder (its NAME.NNNN.h5 snapshots). The slice
holds the particles within one smoothing length of the plane z = z_com (the
orbit lies in the x-y plane, docs/scene.md [collision]); each panel is
centred on the centre of mass of all particles. Writes OUT_DIR/collision.png
(or --png) and OUT_DIR/remnants.csv, .png (ci/remnants), and prints the
remnant table.
"""
import argparse
import glob
import os
import subprocess
import sys

import h5py
import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
COLOURS = ["#6b6b6b", "#b5651d", "#4fa3e0", "#2ca02c", "#d62728", "#9467bd"]


def remnants_module():
    """ci/remnants as a module (its scene_info: the materials' names)."""
    import importlib.machinery
    import importlib.util

    path = os.path.join(ROOT, "ci", "remnants")
    loader = importlib.machinery.SourceFileLoader("rubble_remnants", path)
    spec = importlib.util.spec_from_loader("rubble_remnants", loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--times", type=int, default=6, help="number of panels (>= 4)")
    ap.add_argument("--png", default=None)
    a = ap.parse_args()
    files = sorted(glob.glob(os.path.join(a.out, "*.[0-9][0-9][0-9][0-9].h5")))
    if len(files) < 2:
        print("plot_collision: %s holds fewer than two snapshots" % a.out, file=sys.stderr)
        return 2
    n = max(4, a.times)
    picks = sorted(set(int(round(k)) for k in np.linspace(0, len(files) - 1, n)))
    cols = (len(picks) + 1) // 2
    fig, axes = plt.subplots(2, cols, figsize=(4.2 * cols, 8.4), squeeze=False)
    names = None
    extent = None
    for ax, k in zip(axes.flat, picks):
        with h5py.File(files[k], "r") as f:
            if names is None:
                names = remnants_module().scene_info(f)[1]
            x = f["x"][:]
            h = f["h"][:]
            m = f["m"][:]
            mat = f["material_id"][:]
            t = float(f.attrs["time"]) if "time" in f.attrs else float("nan")
        c = (m[:, None] * x).sum(0) / m.sum()
        s = np.abs(x[:, 2] - c[2]) < h
        if extent is None:  # the first panel's size for all: the bodies' start
            extent = 1.1 * np.max(np.abs(x[:, :2] - c[:2]))
        for mid in np.unique(mat):
            sel = s & (mat == mid)
            label = names[mid] if names and mid < len(names) else "material %d" % mid
            ax.scatter((x[sel, 0] - c[0]) / 1e3, (x[sel, 1] - c[1]) / 1e3, s=4, c=COLOURS[mid % len(COLOURS)],
                       label=label, linewidths=0)
        ax.set_xlim(-extent / 1e3, extent / 1e3)
        ax.set_ylim(-extent / 1e3, extent / 1e3)
        ax.set_aspect("equal")
        ax.set_title("t = %.0f s" % t)
        ax.set_xlabel("x [km]")
        ax.set_ylabel("y [km]")
    for ax in list(axes.flat)[len(picks):]:
        ax.axis("off")
    axes.flat[0].legend(loc="upper left", markerscale=3, fontsize=8)
    fig.suptitle("slice |z - z_com| < h, coloured by material (%s)" % os.path.basename(os.path.normpath(a.out)))
    fig.tight_layout()
    png = a.png or os.path.join(a.out, "collision.png")
    fig.savefig(png, dpi=110)
    print("plot: %s" % png)
    # the bound remnants of the last snapshot
    r = subprocess.run([sys.executable, os.path.join(ROOT, "ci", "remnants"), files[-1], "--out", a.out])
    return r.returncode


if __name__ == "__main__":
    sys.exit(main())
