"""Extra report plots of the soil-forces rung (ci/report calls plots()):
the force per metre on the pushed wall (passive earth pressure) or the
footing's bearing pressure against time at each resolution, with the
reference (Rankine, Prandtl) and the +-10 % band of the check, and where
the plateau that is averaged begins."""
from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import save_figure  # noqa: E402


def plots(case: str, records: list, out_dir: Path) -> list:
    """One figure per case: every resolution's force against time."""
    records = sorted((r for r in records if r.get("series") and r.get("reference", {}).get("F_R")),
                     key=lambda r: r.get("resolution", 0))
    if not records:
        return []
    r0 = records[0]
    ref = r0["reference"]["F_R"]
    p = r0.get("parameters", {})
    bearing = r0.get("setup") == "bearing"
    per = "width" if bearing else "depth"
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for k, r in enumerate(records):
        s = r["series"]
        ax.plot(s["t"], s["force"], color=f"C{k}", lw=1, label=f"{s['per_depth']:.0f} particles per {per}")
    ax.axhline(ref, color="k", ls="--", label="Prandtl (π + 2) c" if bearing else "Rankine F_R")
    for f in (0.9, 1.1):
        ax.axhline(ref * f, color="k", ls=":", lw=0.8)
    ax.axvline(p.get("plateau_from", 0), color="grey", lw=0.8)
    ax.set_xlabel("t [s] (wall speed %.3g m/s)" % p.get("wall_speed", 0))
    ax.set_ylabel("bearing pressure [Pa]" if bearing else "force on the wall [N/m]")
    ax.set_title(("bearing capacity" if bearing else "passive earth pressure") +
                 ", phi = %.0f deg, c = %.0f Pa" % (p.get("friction_angle", 0), p.get("cohesion", 0)))
    ax.legend(fontsize=8)
    name = f"soil_forces_{r0.get('case', case)}.png"
    what = "Bearing pressure of the footing" if bearing else "Force on the pushed wall"
    return [save_figure(fig, out_dir, name, what + " against time, the reference (dashed) and the ±10 % band "
                        "(dotted); the plateau is averaged from the grey line on.")]
