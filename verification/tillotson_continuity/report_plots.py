"""Plots of the tillotson_continuity rung for ci/report (see rung_plugin()).

Per Tillotson material: p(eta, u) and c_s(eta, u) as the solver evaluates them
(default options), with the regime boundaries marked: eta = 1 (compressed to
the right), u = E_iv and u = E_cv for eta < 1 (expanded cold below, partial
vaporisation between, expanded hot above), the tested tension cut-off
eta = rho_limit (dashed), and on the c_s map the states where the sound-speed
floor c^2 = A/rho0 applies (hatched).
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.colors as mcolors  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "verification" / "common"))
from report_figures import save_figure  # noqa: E402


def _newest_with_maps(records):
    best = None
    for r in records:
        if isinstance(r.get("maps"), dict) and (best is None or str(r.get("timestamp", "")) > str(best.get("timestamp", ""))):
            best = r
    return best


def _boundaries(ax, m, eta_min, u_top):
    e_iv, e_cv = m["E_iv"], m["E_cv"]
    ax.axvline(1.0, color="k", lw=1.2)
    ax.plot([eta_min, 1.0], [e_iv, e_iv], color="k", lw=1.2)
    ax.plot([eta_min, 1.0], [e_cv, e_cv], color="k", lw=1.2)
    rl = m.get("rho_limit_tested")
    if rl:
        ax.plot([rl, rl], [ax.get_ylim()[0], e_cv], color="k", lw=1.0, ls="--")
    kw = dict(fontsize=7, ha="center", va="center",
              bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.75))
    ax.text(0.65 * (eta_min + 1.0), e_iv ** 0.5 * ax.get_ylim()[0] ** 0.5, "expanded\ncold", **kw)
    ax.text(0.65 * (eta_min + 1.0), (e_iv * e_cv) ** 0.5, "partial\nvap.", **kw)
    ax.text(0.65 * (eta_min + 1.0), (e_cv * u_top) ** 0.5, "expanded\nhot", **kw)
    ax.text(3.0, (e_iv * e_cv) ** 0.5, "compressed", **kw)
    if rl:
        ax.text(rl, ax.get_ylim()[0] * 3, f"rho_limit={rl:g}", fontsize=6, rotation=90, ha="right", va="bottom")


def plots(case, records, out_dir):
    rec = _newest_with_maps(records)
    if rec is None:
        return []
    m = rec["maps"]
    eta = np.asarray(m["eta"], float)
    u = np.asarray(m["u"], float)
    p = np.asarray(m["p"], float)      # [eta][u]
    cs = np.asarray(m["cs"], float)
    floored = np.asarray(m.get("floored", np.zeros_like(p)), float)
    keep = u > 0                        # u = 0 cannot sit on a log axis
    u, p, cs, floored = u[keep], p[:, keep], cs[:, keep], floored[:, keep]
    A = rec.get("parameters", {}).get("A", np.nanmax(np.abs(p)))

    fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.8), constrained_layout=True)
    E, U = np.meshgrid(eta, u, indexing="ij")

    ax = axes[0]
    norm = mcolors.SymLogNorm(linthresh=1e-3 * A, vmin=-np.nanmax(np.abs(p)), vmax=np.nanmax(np.abs(p)), base=10)
    im = ax.pcolormesh(E, U, p, norm=norm, cmap="RdBu_r", shading="nearest")
    fig.colorbar(im, ax=ax, label="p [Pa] (symmetric log, linear within ±1e-3 A)")
    ax.set_title(f"{case}: pressure p(η, u)")

    ax = axes[1]
    im = ax.pcolormesh(E, U, cs, norm=mcolors.LogNorm(vmin=np.nanmin(cs[cs > 0]), vmax=np.nanmax(cs)),
                       cmap="viridis", shading="nearest")
    fig.colorbar(im, ax=ax, label="c_s [m/s] (log)")
    if floored.any():
        ax.contourf(E, U, floored, levels=[0.5, 1.5], colors="none", hatches=["////"])
        ax.contour(E, U, floored, levels=[0.5], colors="w", linewidths=0.8)
    ax.set_title(f"{case}: sound speed c_s(η, u); hatched: floor c² = A/ρ₀")

    for ax in axes:
        ax.set_yscale("log")
        ax.set_xlabel("η = ρ/ρ₀")
        ax.set_ylabel("u [J/kg]")
        ax.set_xlim(eta.min(), eta.max())
        ax.set_ylim(u.min(), u.max())
        _boundaries(ax, m, eta.min(), u.max())

    name = f"tillotson_continuity-{case}-maps.png"
    return [save_figure(fig, out_dir, name, f"p and c_s maps, regime boundaries: {case}")]
