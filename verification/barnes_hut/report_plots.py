"""Extra report plots of the Barnes-Hut rung (ci/report calls plots()).

- accuracy cases: relative acceleration error (median, 99th percentile)
  against the opening angle theta, one line per multipole order and tree
  setting, with the PHYSICS.md §6 table values (the checks' thresholds) as
  black markers;
- timing cases: wall time of tree build, walk, build + walk and direct
  summation against N (log-log), with the fitted exponents.
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
    return re.sub(r"[^A-Za-z0-9._-]+", "_", s).strip("_") or "x"


def _error_vs_theta(case: str, records: list, out_dir: Path):
    series = {}
    table = {}  # (order, theta) -> (median, p99) from the checks
    for r in records:
        theta = r.get("theta")
        acc = r.get("errors", {}).get("acc", {})
        if theta is None or theta <= 0 or acc.get("median") is None:
            continue
        p = r.get("parameters", {})
        label = f"{p.get('order', '?')}, leaf {p.get('leaf_size', '?')}, group {p.get('group_size', '?')}"
        series.setdefault(label, []).append((theta, acc["median"], acc.get("p99")))
        for c in r.get("checks", []):
            if "PHYSICS.md" not in c.get("source", ""):
                continue
            key = (p.get("order", "?"), theta)
            med, p99 = table.get(key, (None, None))
            if c["name"].startswith("median"):
                med = c["threshold"]
            elif c["name"].startswith("99th"):
                p99 = c["threshold"]
            table[key] = (med, p99)
    if not series:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), sharey=True)
    for k, (label, pts) in enumerate(sorted(series.items())):
        pts.sort()
        th = [t for t, _, _ in pts]
        style = "-" if "quadrupole" in label else "--"
        axes[0].semilogy(th, [m for _, m, _ in pts], style, marker="o", color=f"C{k}", label=label)
        axes[1].semilogy(th, [q for _, _, q in pts], style, marker="o", color=f"C{k}", label=label)
    for (order, theta), (med, p99) in sorted(table.items()):
        marker = "s" if order == "quadrupole" else "^"
        if med is not None:
            axes[0].semilogy([theta], [med], marker, color="k", markerfacecolor="none")
        if p99 is not None:
            axes[1].semilogy([theta], [p99], marker, color="k", markerfacecolor="none")
    axes[0].plot([], [], "s", color="k", markerfacecolor="none", label="PHYSICS.md §6, quadrupole")
    axes[0].plot([], [], "^", color="k", markerfacecolor="none", label="PHYSICS.md §6, monopole")
    for ax, what in zip(axes, ("median", "99th percentile")):
        ax.set_xlabel("opening angle θ")
        ax.set_title(f"{case}: {what} of |a_tree − a_direct| / |a_direct|", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("relative acceleration error")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    name = f"barnes_hut-{_slug(case)}-error_vs_theta.png"
    return save_figure(fig, out_dir, name, f"relative acceleration error vs θ, {case}")


def _time_vs_n(case: str, records: list, out_dir: Path):
    rows = []
    exponents = {}
    for r in records:
        t = r.get("timing")
        if not t or t.get("tree_total") is None or r.get("resolution_name") != "N":
            continue
        rows.append((r["resolution"], t))
        if r.get("observed_order"):
            exponents = r["observed_order"]
    if not rows:
        return None
    rows.sort(key=lambda x: x[0])
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    keys = [("tree_total", "tree build + walk", "tree_time_exponent"),
            ("tree_build", "tree build", "tree_build_exponent"),
            ("tree_walk", "tree walk", "tree_walk_exponent"),
            ("direct", "direct summation", "direct_time_exponent")]
    for k, (key, label, ekey) in enumerate(keys):
        pts = [(n, t[key]) for n, t in rows if t.get(key) is not None]
        if not pts:
            continue
        if exponents.get(ekey) is not None:
            label += f" (N^{exponents[ekey]:.2f})"
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker="o", color=f"C{k}", label=label)
    ax.set_xlabel("N")
    ax.set_ylabel("wall time [s]")
    ax.set_title(f"barnes_hut / {case}: time vs N")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    name = f"barnes_hut-{_slug(case)}-time_vs_n.png"
    return save_figure(fig, out_dir, name, f"wall time vs N, {case}")


def plots(case: str, records: list, out_dir: Path) -> list:
    out = []
    for make in (_error_vs_theta, _time_vs_n):
        img = make(case, records, Path(out_dir))
        if img:
            out.append(img)
    return out
