#!/usr/bin/env python3
"""How rubble's cost grows with the particle count and the thread count
(issue #14 item 4), from rubble_throughput's 3-D hydro case (a periodic
shear layer on a cubic lattice; benchmarks/throughput.cpp).

    python3 benchmarks/scaling.py [--build build] [--out docs/performance_scaling.png]

Runs --case hydro3d at N = 1e4 ... 2e6 with 2 threads, and at 1e5 and 3e5
with 1 thread; prints particle-steps per second, the exponent of the cost
per step in N (least-squares slope of log(N / rate) against log N) and the
parallel efficiency rate(2)/(2 rate(1)); plots rate against N. About four
minutes on 2 cores. The step count per case falls with N to keep the run
short; the rate excludes set-up (throughput.cpp says how).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SIZES = [(10000, 20), (32768, 20), (100000, 10), (300000, 6), (1000000, 4), (2000000, 3)]
ONE_THREAD = [(100000, 10), (300000, 6)]


def run(exe, n, steps, threads):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    out = subprocess.run([str(exe), "--case", "hydro3d", "--n", str(n), "--steps", str(steps)],
                         capture_output=True, text=True, env=env, check=True).stdout
    line = next(l for l in out.splitlines() if l.startswith("RESULT"))
    return int(re.search(r" n=(\d+)", line).group(1)), float(re.search(r" rate=(\S+)", line).group(1))


def slope(xs, ys):
    m = len(xs)
    sx, sy = sum(xs), sum(ys)
    sxx, sxy = sum(x * x for x in xs), sum(x * y for x, y in zip(xs, ys))
    return (m * sxy - sx * sy) / (m * sxx - sx * sx)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=str(REPO / "build"))
    ap.add_argument("--out", default=str(REPO / "docs" / "performance_scaling.png"))
    a = ap.parse_args()
    exe = Path(a.build) / "benchmarks" / "rubble_throughput"

    two = [run(exe, n, k, 2) for n, k in SIZES]
    one = [run(exe, n, k, 1) for n, k in ONE_THREAD]
    print("| particles | particle-steps/s, 2 threads |\n|---|---|")
    for n, r in two:
        print(f"| {n:,} | {r:.3g} |")
    exponent = slope([math.log(n) for n, _ in two], [math.log(n / r) for n, r in two])
    print(f"\ncost per step ~ N^{exponent:.3f}")
    rates2 = dict(two)
    for n, r1 in one:
        print(f"N = {n:,}: 1 thread {r1:.3g}, 2 threads {rates2[n]:.3g}, "
              f"parallel efficiency {rates2[n] / (2 * r1):.2f}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog([n for n, _ in two], [r for _, r in two], "o-", label="2 threads")
    ax.loglog([n for n, _ in one], [r for _, r in one], "s--", label="1 thread")
    ax.set_xlabel("particles")
    ax.set_ylabel("particle-steps per second")
    ax.set_title(f"3-D hydro (rubble_throughput hydro3d): cost ~ N^{exponent:.2f}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"plot: {a.out}")


if __name__ == "__main__":
    main()
