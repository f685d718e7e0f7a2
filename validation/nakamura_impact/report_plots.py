"""Extra report plots for the Nakamura impact rung (called by ci/report).

The damage pattern in the impact plane (the slice |z| < 3 dx/4 of the finest
resolution) at every output, the target's damage history (mean D and the
fraction with D >= 0.99) and the cumulative fragment mass distribution
N(>= M) against M/M_total at every resolution. The experiment's distribution
could not be read here (the records' "experiment" note), so none is drawn.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import save_figure  # noqa: E402


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", s)


def plots(case: str, records: list, out_dir: Path) -> list:
    out = []
    recs = sorted(records, key=lambda r: r["resolution"])
    shots_rec = next((r for r in reversed(recs) if r.get("snapshots")), None)
    if shots_rec:
        shots = shots_rec["snapshots"]
        n = len(shots)
        cols = min(n, 4)
        rows = (n + cols - 1) // cols
        fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.4 * rows), squeeze=False, layout="constrained")
        sc = None
        for k, ax in enumerate(axes.flat):
            if k >= n:
                ax.axis("off")
                continue
            s = shots[k]
            sc = ax.scatter([x * 100 for x in s["x"]], [y * 100 for y in s["y"]], c=s["D"], s=6, cmap="inferno",
                            vmin=0, vmax=1)
            ax.set_aspect("equal")
            ax.set_title(f"t = {s['t'] * 1e6:.1f} µs", fontsize=9)
            if k // cols == rows - 1 or k + cols >= n:  # the lowest panel of its column
                ax.set_xlabel("x [cm]", fontsize=8)
            if k % cols == 0:
                ax.set_ylabel("y [cm]", fontsize=8)
        if sc is not None:
            fig.colorbar(sc, ax=axes, shrink=0.8, label="damage D")
        fig.suptitle(f"target damage in the impact plane (|z| < 3 dx/4), n = {shots_rec['resolution']:g}", fontsize=10)
        name = f"nakamura_impact-{_slug(case)}-damage.png"
        out.append(save_figure(fig, out_dir, name, f"damage pattern, {case}"))

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for j, r in enumerate(recs):
        d = r.get("damage", {})
        t = [x * 1e6 for x in d.get("t", [])]
        axes[0].plot(t, d.get("mean_D", []), "o-", color=f"C{j}", label=f"mean D, n = {r['resolution']:g}")
        axes[0].plot(t, d.get("broken_fraction", []), "s--", color=f"C{j}", label=f"D ≥ 0.99, n = {r['resolution']:g}")
        f = r.get("fragments", {})
        if f.get("mass_fraction"):
            axes[1].loglog(f["mass_fraction"], f["cumulative_number"], "o-", ms=3, color=f"C{j}",
                           label=f"n = {r['resolution']:g}: {f.get('count', 0)} fragments, "
                                 f"largest {f.get('largest_fraction', float('nan')):.3f}")
    axes[0].set_xlabel("t [µs]")
    axes[0].set_ylabel("target fraction")
    axes[0].set_title("damage of the target", fontsize=9)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("fragment mass / total mass")
    axes[1].set_ylabel("cumulative number N(≥ M)")
    axes[1].set_title("fragments at the end (experiment: not found, see the record)", fontsize=9)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    name = f"nakamura_impact-{_slug(case)}-fragments.png"
    out.append(save_figure(fig, out_dir, name, f"damage history and fragment distribution, {case}"))
    return out
