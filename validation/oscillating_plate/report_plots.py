"""Extra report plots for the oscillating-plate rung (called by ci/report).

For one case (all its resolutions together): the tip's y-displacement over
time against the linear first-mode solution A sin(omega t), the amplitude
per half period (decay), the period error against resolution, the energy
history, and the plate's shape at a few times for the coarsest and finest
resolutions (coloured by the shear stress S_xy).
"""
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import particle_panels, save_figure  # noqa: E402


def plots(case, records, out_dir: Path):
    recs = sorted((r for r in records if r.get("tip")), key=lambda r: r["resolution"])
    if not recs:
        return []
    images = []

    fig, ax = plt.subplots(1, 3, figsize=(14, 3.8))
    per = recs[-1]["period"]
    amp_lin = recs[-1]["amplitude"]["theory_linear"]
    omega = per["omega_theory"]
    t_end = max(recs[-1]["tip"]["t"])
    ts = [t_end * i / 400 for i in range(401)]
    ax[0].plot(ts, [amp_lin * math.sin(omega * t) for t in ts], "k--", lw=0.8,
               label=f"linear theory, T = {per['theory']:.4f} s")
    for r in recs:
        lab = f"H/dx = {r['resolution']:g}"
        ax[0].plot(r["tip"]["t"], r["tip"]["y"], label=lab)
        a = r["amplitude"]
        if a.get("t"):
            ax[1].plot(a["t"], a["a"], "o-", ms=3, label=f"{lab}: {100 * a['decay_per_period']:.1f} %/period")
    ax[0].set_xlabel("t [s]")
    ax[0].set_ylabel("tip displacement [m]")
    ax[0].legend(fontsize=7)
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("amplitude per half period [m]")
    ax[1].legend(fontsize=7)
    res = [r["resolution"] for r in recs]
    err = [r["errors"]["period"]["rel"] for r in recs]
    ok = [(x, e) for x, e in zip(res, err) if e is not None and e > 0]
    if ok:
        ax[2].loglog([x for x, _ in ok], [e for _, e in ok], "o-", label="|T - T_theory| / T_theory")
    ax[2].axhline(0.10, color="r", ls="--", lw=0.8, label="limit 10 %")
    ax[2].set_xlabel("particles through the thickness H/dx")
    ax[2].set_ylabel("period error")
    ax[2].legend(fontsize=7)
    fig.suptitle(f"oscillating plate ({case}): tip, amplitude decay, period convergence")
    fig.tight_layout()
    name = f"oscillating_plate-{case}-tip.png"
    images.append(save_figure(fig, out_dir, name, "tip displacement, amplitude decay and period error", dpi=100))

    fig, ax = plt.subplots(figsize=(6, 3.6))
    for r in recs:
        eh = r.get("energy_history")
        if not eh:
            continue
        ke0 = eh["kinetic"][0] or 1.0
        ax.plot(eh["t"], [v / ke0 for v in eh["kinetic"]], label=f"kinetic, H/dx = {r['resolution']:g}")
        ax.plot(eh["t"], [(v - eh["total"][0]) / ke0 for v in eh["total"]], ls="--",
                label=f"total - total(0), H/dx = {r['resolution']:g}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("energy / initial kinetic")
    ax.legend(fontsize=7)
    fig.tight_layout()
    name = f"oscillating_plate-{case}-energy.png"
    images.append(save_figure(fig, out_dir, name, "energy history", dpi=100))

    for r in recs:
        shapes = r.get("shapes") or []
        if not shapes:
            continue
        smax = max(max(abs(v) for v in s["Sxy"]) for s in shapes) or 1.0
        fig = particle_panels(shapes, "Sxy", lambda s: f"t = {s['t']:.3f} s", "$S_{xy}$ [Pa]", panel=(3.0, 2.6),
                              s=1.0, cmap="coolwarm", vmin=-smax, vmax=smax)
        name = f"oscillating_plate-{case}-shapes-{r['resolution']:g}.png"
        images.append(save_figure(fig, out_dir, name, f"plate shapes, H/dx = {r['resolution']:g}", dpi=100))
    return images
