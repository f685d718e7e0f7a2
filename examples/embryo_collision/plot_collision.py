#!/usr/bin/env python3
"""The picture of a rubble collision run: slices through the orbit plane
coloured by material at four or more times, and the bound remnants of the
last snapshot (ci/remnants) as a table.

    python3 examples/embryo_collision/plot_collision.py OUT_DIR [--times 6] [--png FILE]

OUT_DIR is a run's output folder (its NAME.NNNN.h5 snapshots). The first
panel is the start; the others are spread evenly over the snapshots from the
end of the relaxation (simulation.damping_end, when the bodies are launched)
on. The slice holds the particles within one smoothing length of the plane
z = z_c (the orbit lies in the x-y plane, docs/scene.md [collision]); each
panel is centred on c, the median position of the denser half of the
particles (the largest body rather than the ejecta or a far clump). Writes OUT_DIR/collision.png
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
    ap.add_argument("--times", type=int, default=8, help="number of panels (>= 4)")
    ap.add_argument("--png", default=None)
    a = ap.parse_args()
    files = sorted(glob.glob(os.path.join(a.out, "*.[0-9][0-9][0-9][0-9].h5")))
    if len(files) < 2:
        print("plot_collision: %s holds fewer than two snapshots" % a.out, file=sys.stderr)
        return 2
    n = max(4, a.times)
    times = []
    for fn in files:
        with h5py.File(fn, "r") as f:
            times.append(float(f.attrs["time"]))
    with h5py.File(files[0], "r") as f:
        text = f.attrs.get("scene", "")
        text = text.decode() if isinstance(text, bytes) else str(text)
    try:
        import tomllib

        launch = float(tomllib.loads(text).get("simulation", {}).get("damping_end", 0.0))
    except Exception:
        launch = 0.0
    first = next((k for k, t in enumerate(times) if t >= launch * (1 - 1e-9)), 0)
    picks = sorted({0} | set(int(round(k)) for k in np.linspace(first, len(files) - 1, n - 1)))
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
        with h5py.File(files[k], "r") as f:
            rho = f["rho"][:]
        # the median position of the denser half: the largest body, not a far clump
        c = np.median(x[rho >= np.median(rho)], axis=0)
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
    for ax in list(axes.flat)[len(picks):]:  # an odd number of panels
        ax.axis("off")
    axes.flat[0].legend(loc="upper left", markerscale=3, fontsize=8)
    fig.suptitle("slice |z - z_c| < h, coloured by material (%s)" % os.path.basename(os.path.normpath(a.out)))
    fig.tight_layout()
    png = a.png or os.path.join(a.out, "collision.png")
    fig.savefig(png, dpi=110)
    print("plot: %s" % png)
    # the bound remnants of the last snapshot
    r = subprocess.run([sys.executable, os.path.join(ROOT, "ci", "remnants"), files[-1], "--out", a.out],
                       stdout=subprocess.DEVNULL)
    if r.returncode != 0:
        return r.returncode
    print_table(os.path.join(a.out, "remnants.csv"))
    return 0


def print_table(path):
    """The remnants as a table: mass, share, particles and composition."""
    import csv

    with open(path) as f:
        title = f.readline().lstrip("# ").strip()
        rows = list(csv.DictReader(f))
    fracs = [k for k in rows[0] if k.startswith("frac_")] if rows else []
    print(title)
    print("%-10s %12s %8s %9s " % ("group", "mass [kg]", "share", "particles") +
          " ".join("%8s" % k[5:] for k in fracs))
    for row in rows:
        print("%-10s %12.4g %8.4f %9s " % (row["group"], float(row["mass"]), float(row["mass_fraction"]),
                                           row["particles"]) + " ".join("%8.3f" % float(row[k]) for k in fracs))
    print("table: %s (composition: mass fractions by material and by body of origin)" % path)


if __name__ == "__main__":
    sys.exit(main())
