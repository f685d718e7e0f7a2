"""Extra report plots of the polytrope rung (ci/report calls plots()):
the mass-weighted 90 % radius and the energies against time, with the end
of the damped relaxation marked and the ±2 % band of the check."""
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
    return re.sub(r"[^A-Za-z0-9._-]+", "_", s).strip("_") or "x"


def plots(case: str, records: list, out_dir: Path) -> list:
    records = [r for r in records if r.get("series")]
    if not records:
        return []
    r = max(records, key=lambda x: x.get("resolution", 0))
    s = r["series"]
    t_relax = r.get("parameters", {}).get("damping_end")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    ax = axes[0]
    ax.plot(s["snapshot_t"], s["r90"], "o-", ms=3, label="r90 (SPH)")
    if r.get("r90_lane_emden"):
        ax.axhline(r["r90_lane_emden"], color="k", ls=":", label="r90 Lane–Emden")
    if r.get("r90_relaxed"):
        for f in (0.98, 1.02):
            ax.axhline(r["r90_relaxed"] * f, color="C3", ls="--", lw=0.8)
        ax.plot([], [], "--", color="C3", lw=0.8, label="±2 % of relaxed r90")
    ax.set_xlabel("t")
    ax.set_ylabel("mass-weighted 90 % radius")
    ax.legend(fontsize=8)
    ax = axes[1]
    e0 = r.get("energy_after_relaxation", {}).get("total")
    if e0:
        ax.plot(s["t"], [(e - e0) / abs(e0) for e in s["total"]], label="(E − E(t_relax)) / |E(t_relax)|")
        for f in (-0.01, 0.01):
            ax.axhline(f, color="C3", ls="--", lw=0.8)
        ax.plot([], [], "--", color="C3", lw=0.8, label="±1 % (check)")
        lo = min(min((e - e0) / abs(e0) for e in s["total"]), -0.0)
        ax.set_ylim(min(lo * 1.2, -0.012), 0.012)
    ax.set_xlabel("t")
    ax.set_ylabel("relative change of the total energy")
    ax.legend(fontsize=8)
    for ax in axes:
        if t_relax:
            ax.axvline(t_relax, color="grey", lw=0.8)
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"polytrope / {case}, N = {r.get('n_particles')} (grey: end of damping)", fontsize=10)
    fig.tight_layout()
    name = f"polytrope-{_slug(case)}-radius_energy.png"
    return [save_figure(fig, out_dir, name, f"radius and energy vs time, {case}")]
