"""Extra report plots for the rubber-ring rung (called by ci/report).

Per record (one resolution or variant): the energy history (kinetic,
internal, total, relative to the initial kinetic energy), the ring
diagnostics over time (centre-of-mass x-velocities, closest pair / dx,
number of connected bodies), and a strip of density snapshots.
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import particle_panels, save_figure  # noqa: E402


def _tag(rec):
    p = rec.get("parameters", {})
    tag = f"dx{p.get('dx', rec.get('resolution'))}"
    if p.get("artificial_stress") is False:
        tag += "-no-artificial-stress"
    return tag


def plots(case, records, out_dir: Path):
    images = []
    for rec in records:
        tag = _tag(rec)
        eh, outs, strip = rec.get("energy_history"), rec.get("outputs"), rec.get("density_strip")
        if eh and outs:
            fig, ax = plt.subplots(1, 3, figsize=(13, 3.6))
            ke0 = eh["kinetic"][0] if eh["kinetic"][0] else 1.0
            for key in ("kinetic", "internal", "total"):
                ax[0].plot(eh["t"], [v / ke0 for v in eh[key]], label=key)
            ax[0].set_xlabel("t")
            ax[0].set_ylabel("energy / initial kinetic")
            ax[0].legend(fontsize=8)
            ax[1].plot(outs["t"], outs["vcom_left"], label="left ring")
            ax[1].plot(outs["t"], outs["vcom_right"], label="right ring")
            ax[1].axhline(0, color="k", lw=0.5)
            ax[1].set_xlabel("t")
            ax[1].set_ylabel("centre-of-mass $v_x$")
            ax[1].legend(fontsize=8)
            ax[2].plot(outs["t"], outs["min_pair_over_dx"], label="closest pair / dx")
            ax[2].axhline(0.5, color="r", lw=0.8, ls="--", label="limit 0.5 dx")
            ax2 = ax[2].twinx()
            ax2.step(outs["t"], outs["bodies"], where="post", color="gray", label="bodies")
            ax2.set_ylabel("connected bodies")
            ax[2].set_xlabel("t")
            ax[2].set_ylabel("closest pair / dx")
            ax[2].legend(fontsize=8, loc="lower left")
            fig.suptitle(f"rubber rings {tag}: energy and diagnostics")
            fig.tight_layout()
            name = f"rubber_rings-{case}-{tag}-history.png"
            images.append(save_figure(fig, out_dir, name, f"energy and diagnostics {tag}", dpi=100))
        if strip:
            fig = particle_panels(strip, "rho", lambda snap: f"t = {snap['t']:g}", "density", panel=(3.2, 3.0),
                                  s=0.5, cmap="viridis", vmin=0.9, vmax=1.1)
            name = f"rubber_rings-{case}-{tag}-density.png"
            images.append(save_figure(fig, out_dir, name, f"density snapshots {tag}", dpi=100))
    return images
