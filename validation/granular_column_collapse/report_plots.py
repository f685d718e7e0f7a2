"""Extra report plots for the granular column collapse rung (called by ci/report).

Column cases (records with "snapshots"/"profile"): the collapse at several
times coloured by the accumulated plastic strain eps_p (finest resolution;
the rung's raster of each snapshot),
the final free-surface profiles of every resolution over the experimental
profile and failure line of Bui et al. 2008 (as digitised, see the records'
reference_sources) with the fitted failure lines, and the kinetic-energy
history. Aspect-ratio sweep (records with "sweep"): (L_inf - L0)/L0 and
H_inf/L0 against a = H0/L0 with the fitted power laws beside the 2-D laws of
Lube et al. 2005 and Lajeunesse et al. 2005 (as quoted by secondary sources).
"""
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import save_figure  # noqa: E402


def _lube(a):
    return 1.2 * a if a <= 1.8 else 1.9 * a ** (2.0 / 3.0)


def _lajeunesse(a):
    return 1.8 * a if a < 3.0 else 2.3 * a ** (2.0 / 3.0)


def _eps_values(s):
    """eps_p of a snapshot as a list of finite values (for the colour scale)."""
    if "raster" in s:
        return [v for v in s["raster"]["eps_p"] if v is not None]
    return list(s["eps_p"])


def _snapshot_plot(case, rec, out_dir):
    """The collapse at the recorded times, coloured by eps_p: the rung's
    raster (cells of max(dx, H0/50), empty outside the material) where the
    record has one, else the particle subsample of older records."""
    shots = rec["snapshots"]
    n = len(shots)
    x_ends = [s["raster"]["x0"] + s["raster"]["nx"] * s["raster"]["cell"] for s in shots if "raster" in s]
    x_max = max([0.5, rec["runout"]["toe"] + 0.02] + x_ends)
    y_max = 0.11 * rec["H0"] / 0.1
    panel_h = 7.6 * (y_max + 0.005) / (x_max + 0.01)  # equal aspect over a 7.6 in wide panel
    fig, axes = plt.subplots(n, 1, figsize=(9, n * (panel_h + 0.25) + 1.1), squeeze=False, sharex=True,
                             layout="constrained")
    vmax = min(3.0, max([1.0] + [max(_eps_values(s), default=0.0) for s in shots]))
    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="white")
    im = None
    for ax, s in zip(axes[:, 0], shots):
        if "raster" in s:
            g = s["raster"]
            nx, ny, c = g["nx"], g["ny"], g["cell"]
            vals = np.array([np.nan if v is None else v for v in g["eps_p"]], dtype=float).reshape(ny, nx)
            im = ax.imshow(np.ma.masked_invalid(vals), origin="lower", interpolation="nearest", cmap=cmap,
                           vmin=0.0, vmax=vmax,
                           extent=(g["x0"], g["x0"] + nx * c, g["y0"], g["y0"] + ny * c))
        else:
            im = ax.scatter(s["x"], s["y"], c=s["eps_p"], s=0.6, cmap="viridis", vmin=0.0, vmax=vmax)
        # the floor and the back wall (the raster reaches 0.8 dx beyond the particles)
        ax.axhspan(-0.005, 0.0, color="0.6", zorder=3)
        ax.axvspan(-0.01, 0.0, color="0.6", zorder=3)
        ax.set_aspect("equal")
        ax.set_xlim(-0.01, x_max)
        ax.set_ylim(-0.005, y_max)
        ax.text(0.99, 0.85, f"t = {s['t']:.3f} s", transform=ax.transAxes, ha="right", fontsize=8)
        ax.set_ylabel("y [m]", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("x [m]")
    fig.colorbar(im, ax=axes[:, 0].tolist(), orientation="horizontal", fraction=0.04, aspect=50,
                 label="accumulated plastic strain $\\varepsilon_p$ (clipped at %.1f)" % vmax)
    fig.suptitle(f"column collapse ({case}), H0/dx = {rec['resolution']:g}", fontsize=10)
    name = f"granular_column_collapse-{case}-snapshots.png"
    return save_figure(fig, out_dir, name, f"collapse coloured by eps_p, H0/dx = {rec['resolution']:g}")


def _column_plots(case, recs, out_dir):
    images = []
    recs = sorted(recs, key=lambda r: r["resolution"])
    shots_rec = next((r for r in reversed(recs) if r.get("snapshots")), None)
    if shots_rec:
        images.append(_snapshot_plot(case, shots_rec, out_dir))

    fig, ax = plt.subplots(figsize=(9, 3.6))
    ref = recs[-1]
    exact = ref["profile"]["exact"]
    ax.plot(exact["x"], exact["h"], "ks", ms=4, label="experiment, surface (Bui et al. 2008, digitised)")
    fl = ref["failure_line"]
    ax.plot(fl["experiment_x"], fl["experiment_y"], "k^--", ms=4, lw=0.8,
            label=f"experiment, failure line ({fl['experiment_angle']:.1f} deg fit)")
    for r in recs:
        p = r["profile"]
        line, = ax.plot(p["x"], p["h"], lw=1.2,
                        label=f"H0/dx = {r['resolution']:g}: toe {r['runout']['toe']:.3f} m")
        end = r["failure_line"]["end"]
        if end.get("slope") is not None and end.get("x"):
            xs = [min(end["x"]), max(end["x"])]
            ax.plot(xs, [end["intercept"] + end["slope"] * x for x in xs], ls=":", color=line.get_color(),
                    label=f"  failure line (eps_p > {r['failure_line']['threshold']:g}) {end['angle']:.1f} deg")
    ax.axvline(ref["runout"]["lube2005"], color="grey", ls="--", lw=0.7, label="Lube 2005 law runout")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("height [m]")
    ax.set_xlim(0, max(0.5, max(r["runout"]["toe"] for r in recs) + 0.02))
    ax.set_ylim(0, 0.11 * ref["H0"] / 0.1)
    ax.legend(fontsize=6.5, ncol=2)
    ax.set_title(f"final profiles ({case})", fontsize=10)
    fig.tight_layout()
    name = f"granular_column_collapse-{case}-profiles_final.png"
    images.append(save_figure(fig, out_dir, name,
                              "final free-surface profiles and failure lines against the experiment"))

    # The front magnified: the profiles' last few centimetres of height, with
    # the front at each measured thickness (record "front", where present).
    fig, ax = plt.subplots(figsize=(9, 3.2))
    ax.plot(exact["x"], exact["h"], "ks-", ms=4, lw=0.8, label="experiment (Bui et al. 2008, digitised)")
    fr = ref.get("front")
    if fr:
        for f, xe in zip(fr["thickness_over_H0"], fr["experiment"]):
            hh = f * ref["H0"]
            ax.axhline(hh, color="grey", ls=":", lw=0.6)
            if xe is not None:
                ax.plot([xe], [hh], "kx", ms=7)
    for r in recs:
        p = r["profile"]
        line, = ax.plot(p["x"], p["h"], lw=1.2, label=f"H0/dx = {r['resolution']:g}: toe {r['runout']['toe']:.3f} m")
        f = r.get("front")
        if f:
            pts = [(x, t * r["H0"]) for x, t in zip(f["x"], f["thickness_over_H0"]) if x is not None]
            if pts:
                ax.plot(*zip(*pts), "o", ms=4, color=line.get_color())
    ax.set_xlim(0.28, max(0.5, max(r["runout"]["toe"] for r in recs) + 0.02))
    ax.set_ylim(0, 0.25 * ref["H0"])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("height [m]")
    ax.legend(fontsize=7)
    ax.set_title(f"the front magnified ({case}): dotted, the thicknesses where the front is measured "
                 "(x experiment, o simulation)", fontsize=9)
    fig.tight_layout()
    name = f"granular_column_collapse-{case}-front.png"
    levels = (", ".join(f"{f:g}" for f in fr["thickness_over_H0"]) + " H0") if fr else \
        "a thickness (not in this older record)"
    images.append(save_figure(fig, out_dir, name, f"the front magnified: where the surface first falls below {levels}"))

    fig, ax = plt.subplots(figsize=(6, 3.4))
    for r in recs:
        k = r.get("kinetic")
        if not k or not k.get("t"):
            continue
        ax.semilogy(k["t"], [max(v / k["peak"], 1e-12) for v in k["ke"]], label=f"H0/dx = {r['resolution']:g}")
    ax.axhline(1e-4, color="r", ls="--", lw=0.8, label="at rest: 1e-4 of the peak")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("kinetic energy / peak")
    ax.legend(fontsize=7)
    fig.tight_layout()
    name = f"granular_column_collapse-{case}-kinetic.png"
    images.append(save_figure(fig, out_dir, name, "kinetic energy history", dpi=100))
    return images


def _sweep_plots(case, recs, out_dir):
    images = []
    for r in sorted(recs, key=lambda r: r["resolution"]):
        s = r["sweep"]
        a = s["a"]
        fig, ax = plt.subplots(1, 2, figsize=(11, 4))
        aa = [0.3 * (30 / 0.3) ** (i / 200) for i in range(201)]
        ax[0].loglog(a, s["normalised_runout"], "o", ms=6, label=f"rubble, slope {s['slope_runout']:.2f}")
        # fitted power law through the points
        la = [math.log(x) for x in a]
        ly = [math.log(y) for y in s["normalised_runout"]]
        c = sum(ly) / len(ly) - s["slope_runout"] * sum(la) / len(la)
        ax[0].loglog(aa, [math.exp(c) * x ** s["slope_runout"] for x in aa], "C0-", lw=0.8)
        ax[0].loglog(aa, [_lube(x) for x in aa], "k--", lw=0.9, label="Lube et al. 2005 (1.2a; 1.9a^(2/3))")
        ax[0].loglog(aa, [_lajeunesse(x) for x in aa], "k:", lw=0.9,
                     label="Lajeunesse et al. 2005 (1.8a; 2.3a^(2/3))")
        e = s.get("experiment")
        if e:  # the aluminium bars of Bui et al. 2008 at a = 0.5 (the laws are fits to other materials)
            ax[0].loglog([e["a"]], [e["normalised_runout"]], "k*", ms=10,
                         label="Bui et al. 2008 experiment (aluminium bars, digitised)")
        ax[0].set_xlim(0.3, 8)
        ax[0].set_xlabel("a = H0/L0")
        ax[0].set_ylabel("(L_inf - L0)/L0")
        ax[0].legend(fontsize=7)
        ax[1].loglog(a, s["normalised_height"], "o", ms=6, label=f"rubble, slope {s['slope_height']:.2f}")
        ly = [math.log(y) for y in s["normalised_height"]]
        c = sum(ly) / len(ly) - s["slope_height"] * sum(la) / len(la)
        ax[1].loglog(aa, [math.exp(c) * x ** s["slope_height"] for x in aa], "C0-", lw=0.8)
        ax[1].loglog(aa, aa, "k--", lw=0.6, label="H_inf = H0 (no collapse)")
        if e:
            ax[1].loglog([e["a"]], [e["normalised_height"]], "k*", ms=10, label="Bui et al. 2008 experiment")
        ax[1].set_xlim(0.3, 8)
        ax[1].set_xlabel("a = H0/L0")
        ax[1].set_ylabel("H_inf/L0")
        ax[1].legend(fontsize=7)
        for axis in ax:  # ticks at the swept ratios, no crowded minor labels
            axis.set_xticks([0.5, 1, 2, 4])
            axis.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
            axis.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        fig.suptitle(f"aspect-ratio sweep ({case}), dx = {r['dx']:g} m (laws as quoted by secondary sources)",
                     fontsize=10)
        fig.tight_layout()
        name = f"granular_column_collapse-{case}-runout_vs_a-{r['resolution']:g}.png"
        images.append(save_figure(fig, out_dir, name,
                                  f"normalised runout and height against a, resolution {r['resolution']:g}"))

        fig, ax = plt.subplots(figsize=(9, 3.4))
        for run in s["runs"]:
            ax.plot(run["profile_x"], run["profile_h"], label=f"a = {run['a']:.3g}")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("height [m]")
        ax.legend(fontsize=7)
        fig.tight_layout()
        name = f"granular_column_collapse-{case}-sweep_profiles-{r['resolution']:g}.png"
        images.append(save_figure(fig, out_dir, name,
                                  f"final profiles of the sweep, resolution {r['resolution']:g}", dpi=100))
    return images


def plots(case, records, out_dir: Path):
    sweep = [r for r in records if r.get("sweep")]
    column = [r for r in records if r.get("profile") and r.get("failure_line")]
    images = []
    if column:
        images += _column_plots(case, column, out_dir)
    if sweep:
        images += _sweep_plots(case, sweep, out_dir)
    return images
