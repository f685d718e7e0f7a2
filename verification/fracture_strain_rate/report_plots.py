"""Extra report plots of the fracture strain-rate rung (ci/report calls plots()).

- failure stress against strain rate (log-log): measured sigma_f, the
  mean-field Grady-Kipp stress sigma_GK of fracture_rung.cpp, and the fitted
  line over the dynamic rates beside the theory slope 1/(m+1);
- failure stress against specimen volume at the quasi-static rate: measured
  sigma_f and the weakest flaw's E eps_1 ~ V^(-1/m);
- the bar's mean acting stress against its strain eps_dot t, one line per rate.
"""
from __future__ import annotations

import math
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


def _fit(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    slope = sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx
    return slope, my - slope * mx


def plots(case: str, records: list, out_dir: Path) -> list:
    out = []
    for k, r in enumerate(records):
        m = r.get("measures", {})
        if not m.get("rates") or not m.get("sigma_f"):
            continue
        p = r.get("parameters", {})
        tag = f"cap {p.get('cap', 'active_fraction')}, {p.get('min_flaws_per_particle', 1)} flaws/particle min"
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
        ax = axes[0]
        rates, sig = m["rates"], m["sigma_f"]
        ax.loglog(rates, [s / 1e6 for s in sig], "o-", label="measured $\\sigma_f$")
        if m.get("sigma_gk_mean_field"):
            ax.loglog(rates, [s / 1e6 for s in m["sigma_gk_mean_field"]], "k--",
                      label="mean-field Grady-Kipp $\\sigma_{GK}$")
        dyn = [(x, y) for x, y in zip(rates, sig) if x in m.get("dynamic_rates", [])]
        if len(dyn) >= 2:
            slope, icpt = _fit([x for x, _ in dyn], [y for _, y in dyn])
            xs = [dyn[0][0], dyn[-1][0]]
            ax.loglog(xs, [math.exp(icpt) * x ** slope / 1e6 for x in xs], "r-", lw=3, alpha=0.4,
                      label=f"fit over dynamic rates: slope {slope:.3f} (theory {m.get('theory_rate', float('nan')):.3f})")
        ax.set_xlabel("strain rate [1/s]")
        ax.set_ylabel("failure stress [MPa]")
        ax.set_title(f"strain-rate law ({tag})", fontsize=9)
        ax.legend(fontsize=7)
        ax = axes[1]
        if m.get("volumes") and m.get("sigma_f_size"):
            ax.loglog(m["volumes"], [s / 1e6 for s in m["sigma_f_size"]], "o-",
                      label=f"measured (slope {m.get('slope_size', float('nan')):.3f})")
            if m.get("sigma_weakest_flaw"):
                ax.loglog(m["volumes"], [s / 1e6 for s in m["sigma_weakest_flaw"]], "k--",
                          label=f"weakest flaw $E\\epsilon_1$ (slope {m.get('theory_size', float('nan')):.3f})")
            ax.set_xlabel("specimen volume [m$^3$]")
            ax.set_ylabel("failure stress [MPa]")
            ax.set_title(f"size effect at {p.get('quasi_static_rate', '?')} /s", fontsize=9)
            ax.legend(fontsize=7)
        ax = axes[2]
        for j, h in enumerate(m.get("histories", [])):
            rate = h["rate"]
            ax.plot([rate * t * 1e3 for t in h["t"]], [s / 1e6 for s in h["sigma"]], color=f"C{j % 10}",
                    label=f"{rate:g} /s")
        ax.set_xlabel("bar strain $\\dot\\epsilon t$ [10$^{-3}$]")
        ax.set_ylabel("mean acting $\\sigma_{xx}$ [MPa]")
        ax.set_title("stress histories", fontsize=9)
        ax.legend(fontsize=7)
        fig.tight_layout()
        name = f"fracture_strain_rate-{_slug(case)}-{k}-laws.png"
        out.append(save_figure(fig, out_dir, name, f"failure stress against rate and volume, {case}"))
    return out
