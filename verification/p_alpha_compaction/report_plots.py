"""Plots of the p_alpha_compaction rung for ci/report (see rung_plugin()).

forced_* cases (0-D forced evolution): the alpha(p) trajectory of the finest
step over the crush curve and the virgin elastic curve, alpha(t) against the
exact envelope solution, and the convergence of the global alpha error with
the step (with a slope-2 reference line: Heun).

piston_* cases (planar compaction, Jutzi et al. 2008 §5.1): rho, p, alpha, v
against x for the finest resolution with the analytic two-wave solution,
the measured and analytic front positions marked, and the L1 errors against
resolution beside Spheral's regression values at N = 500.

impact* cases (2-D impact into porous basalt): alpha(p) of the porous
particles over the crush curve and the compacted zone.
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import save_figure  # noqa: E402


def _finest(records, key):
    best = None
    for r in records:
        if isinstance(r.get(key), dict) and r[key]:
            if best is None or r.get("resolution", 0) > best.get("resolution", 0):
                best = r
    return best


def _forced(case, records, out_dir):
    images = []
    rec = _finest(records, "profile")
    if rec is not None:
        prof, traj = rec["profile"], rec.get("trajectory", {})
        par = rec.get("parameters", {})
        fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.6), constrained_layout=True)
        ax = axes[0]
        ex = prof["exact"]
        ax.plot(np.asarray(ex["x"]) / 1e6, ex["alpha"], "k-", lw=1.2, label="crush curve α_c(p)")
        ax.plot(np.asarray(ex["x"]) / 1e6, ex["alpha_elastic"], "k:", lw=1.0, label="virgin elastic curve α_el(p)")
        ax.plot(np.asarray(prof["x"]) / 1e6, prof["alpha"], "C3-", lw=0.9, alpha=0.8,
                label=f"Heun, dt = 1/{rec['resolution']:g}")
        for k, ls in (("p_e", "--"), ("p_t", "-."), ("p_s", "--")):
            v = par.get(k)
            if v:
                ax.axvline(v / 1e6, color="0.6", ls=ls, lw=0.8)
        ax.set_xlabel("p [MPa]")
        ax.set_ylabel("α")
        ax.set_title(f"{case}: α(p) trajectory (load, unload, reload, unload)")
        ax.legend(fontsize=8)
        ax = axes[1]
        if traj:
            ax.plot(traj["t"], traj["alpha_exact"], "k-", lw=1.2, label="exact (envelope at the running max of ρ)")
            ax.plot(traj["t"], traj["alpha"], "C3--", lw=0.9, label="Heun")
        ax.set_xlabel("t (forcing periods)")
        ax.set_ylabel("α")
        ax.set_title("α(t)")
        ax.legend(fontsize=8)
        name = f"p_alpha_compaction-{case}-trajectory.png"
        images.append(save_figure(fig, out_dir, name, f"α(p) over the crush curve and α(t): {case}"))
    pts = sorted((r["resolution"], r["errors"]["alpha"].get("Linf")) for r in records
                 if "alpha" in r.get("errors", {}) and r["errors"]["alpha"].get("Linf"))
    if len(pts) >= 2:
        res = np.array([p[0] for p in pts], float)
        err = np.array([p[1] for p in pts], float)
        fig, ax = plt.subplots(figsize=(5.6, 4.4), constrained_layout=True)
        ax.loglog(1 / res, err, "o-", label="max_n |α_n − α(t_n)|")
        ax.loglog(1 / res, err[-1] * (res[-1] / res) ** 2, "k:", label="slope 2")
        ax.set_xlabel("dt (forcing periods)")
        ax.set_ylabel("global α error")
        ax.set_title(f"{case}: convergence in dt")
        ax.legend(fontsize=8)
        name = f"p_alpha_compaction-{case}-dt_convergence.png"
        images.append(save_figure(fig, out_dir, name, f"α error against the step: {case}"))
    return images


def _piston(case, records, out_dir):
    images = []
    rec = _finest(records, "profile")
    if rec is not None:
        prof, ex = rec["profile"], rec["profile"]["exact"]
        fr = rec.get("fronts", {})
        x = np.asarray(prof["x"]) * 1e3
        xe = np.asarray(ex["x"]) * 1e3
        fields = [("rho", "ρ [kg/m³]", 1.0), ("p", "p [GPa]", 1e-9), ("alpha", "α", 1.0), ("v", "v [m/s]", 1.0)]
        fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), constrained_layout=True)
        for ax, (k, label, s) in zip(axes.flat, fields):
            ax.plot(x, np.asarray(prof[k]) * s, ".", ms=2.5, color="C0", label=f"SPH, N = {rec['resolution']:g}")
            ax.plot(xe, np.asarray(ex[k]) * s, "k-", lw=1.1, label="two-wave solution")
            for name, ls in (("compaction", "--"), ("elastic", ":")):
                f = fr.get(name, {})
                if f.get("sph") is not None:
                    ax.axvline(f["sph"] * 1e3, color="C3", ls=ls, lw=0.8)
            ax.set_xlabel("x [mm] (wall at 0)")
            ax.set_ylabel(label)
            ax.set_xlim(0, max(xe) if len(xe) else None)
        axes[0, 0].legend(fontsize=8)
        fig.suptitle(f"{case}: piston compaction at t = {rec.get('parameters', {}).get('t', 0) * 1e6:.3g} µs "
                     "(red: measured fronts, dashed compaction, dotted elastic)")
        name = f"p_alpha_compaction-{case}-profiles_vs_exact.png"
        images.append(save_figure(fig, out_dir, name, f"profiles with the analytic solution: {case}"))
    rows = sorted((r["resolution"], r) for r in records if "errors" in r)
    if len(rows) >= 2:
        res = np.array([q[0] for q in rows], float)
        fig, axes = plt.subplots(1, 4, figsize=(15, 3.8), constrained_layout=True)
        for ax, k in zip(axes, ("rho", "alpha", "v", "p")):
            e = np.array([q[1]["errors"][k]["L1"] or np.nan for q in rows], float)
            g = np.array([q[1].get("errors_spheral_definition", {}).get(k, np.nan) for q in rows], float)
            ax.loglog(res, e, "o-", label="L1, window [0, 1.25 x_e]")
            ax.loglog(res, g, "s--", label="L1, Spheral's definition")
            ref = rows[-1][1].get("spheral_reference_L1", {})
            if ref.get(k):
                ax.loglog([ref.get("resolution", 500)], [ref[k]], "k*", ms=10, label="Spheral SPH (regression value)")
            ax.loglog(res, e[0] * res[0] / res, "k:", lw=0.8, label="slope −1")
            ax.set_xlabel("N per rod")
            ax.set_title(f"L1({k})")
        axes[0].legend(fontsize=7)
        name = f"p_alpha_compaction-{case}-l1_vs_spheral.png"
        images.append(save_figure(fig, out_dir, name, f"L1 errors against resolution, with Spheral's values: {case}"))
    return images


def _impact(case, records, out_dir):
    """The 2-D impact into porous basalt: (p, alpha) of every porous particle
    at the last output over the crush curve, and the alpha field near the
    impact point (the compacted zone)."""
    rec = _finest(records, "impact")
    if rec is None:
        return []
    im, par = rec["impact"], rec.get("parameters", {})
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), constrained_layout=True)
    ax = axes[0]
    ax.plot(np.asarray(im["crush_p"]) / 1e9, im["crush_alpha"], "k-", lw=1.2, label="crush curve α_c(p)")
    ax.scatter(np.asarray(im["p"]) / 1e9, im["alpha"], s=2, c="C0", alpha=0.5, label="porous particles")
    ax.set_xlabel("p [GPa]")
    ax.set_ylabel("α")
    ax.set_xlim(min(-0.1, float(np.min(im["p"])) / 1e9), 1.2 * par.get("p_s", 2e9) / 1e9)
    ax.legend(fontsize=8)
    ax.set_title(f"on or below the crush curve at t = {par.get('t_end', 0) * 1e6:.3g} µs")
    ax = axes[1]
    sc = ax.scatter(np.asarray(im["map_x"]) * 1e3, np.asarray(im["map_y"]) * 1e3, c=im["map_alpha"], s=3,
                    cmap="viridis", vmin=1.0, vmax=par.get("alpha0", 1.25))
    fig.colorbar(sc, ax=ax, label="α")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"compacted zone, {par.get('impact_speed', 0) / 1e3:.3g} km/s basalt disc "
                 f"(R = {par.get('projectile_radius', 0) * 1e3:.3g} mm)")
    name = f"p_alpha_compaction-{case}-impact.png"
    return [save_figure(fig, out_dir, name,
                        f"porous impact: α(p) over the crush curve and the compacted zone ({case})")]


def plots(case, records, out_dir):
    if case.startswith("forced_"):
        return _forced(case, records, out_dir)
    if case.startswith("impact"):
        return _impact(case, records, out_dir)
    return _piston(case, records, out_dir)
