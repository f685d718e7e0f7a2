#!/usr/bin/env python3
"""Side-by-side: rubble and Phantom on the 3-D Sedov blast wave (issue #14).

Usage (from the repository root, after `cmake --preset ci && cmake --build
build`; Phantom's source in .deps/phantom/src, see README.md here):

    python3 benchmarks/peers/sedov_vs_phantom.py [--threads 2]
        [--small 56:50] [--large 112:100] [--large-steps 10] [--out DIR]
        [--skip-large] [--rubble-only] [--repeat N] [--native]

With --native both codes are compiled for this machine's processor:
Phantom with -march=native in a build folder of its own, rubble from a
build configured with -DRUBBLE_NATIVE=ON (default folder build-native; the
script refuses a rubble build whose RUBBLE_NATIVE does not match).

Two cases, each code as a whole process (set-up included), one after the
other, with the same number of OpenMP threads:

  small  rubble N^3 on a cubic lattice (default 56^3 = 175,616) and Phantom
         npartx (default 50: 50 x 58 x 60 = 174,000 on its close-packed
         lattice), both to t = 0.1: wall time, steps, particle-steps per
         second, peak resident memory, and the shock-radius error of each
         code's own final snapshot, measured by one program
         (`sedov_rung --measure`, verification/sedov_taylor/sedov_measure.hpp)
         against the exact solution.
  large  rubble 112^3 = 1,404,928 and Phantom npartx 100 (1,368,000): Phantom
         runs --large-steps steps; rubble runs to the time Phantom reached,
         and its own step count is used: particle-steps per second and peak
         memory per particle.

Matched: M4 cubic spline with h = 1.2 dx (rubble: support 2.4 dx), ~58
neighbours, summation density with grad-h terms, artificial viscosity fixed
at alpha = 1, beta = 2, artificial conductivity alpha_u = 1, global time
steps with Courant number 0.3, the h-rho iteration stopped at a relative
change of 1e-4 (Phantom's tolh; rubble's simulation.h_tolerance), the blast
energy spread by the cubic spline of support 4.8 dx, ambient u = 0. Phantom's force step factor C_force = 0.25
is its default; rubble's force_factor is its own default (docs/scene.md).

With --repeat N the small case runs N times, rubble and Phantom
alternating, so that both see the same minutes of a shared machine: the
table shows each code's run of median wall time, and the speed ratio of
every pair is listed with its median.

The table is printed and written to OUT/sedov_vs_phantom.md with the JSON
of every measurement (OUT defaults to build/peers). Ratios are rubble over
Phantom (speed) or Phantom over rubble (memory), so > 1 favours rubble.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
from phantom import TOLH  # noqa: E402  (the h-rho tolerance both codes run with)

SCENE = REPO / "verification" / "sedov_taylor" / "sedov_3d.toml"


def parse_pair(text):
    a, b = text.split(":")
    return int(a), int(b)


def peak_rss_kb(time_log):
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", Path(time_log).read_text())
    return int(m.group(1)) if m else None


def measure(rung, columns, t, out_file):
    """Write the particles as the table `sedov_rung --measure` reads, run it."""
    header = f"# time {t!r}\n# x y z vx vy vz m rho u\n"
    table = np.column_stack(columns)
    with open(out_file, "w") as f:
        f.write(header)
        np.savetxt(f, table, fmt="%.17g")
    res = subprocess.run([str(rung), "--measure", str(out_file)], capture_output=True, text=True, check=True)
    return json.loads(res.stdout)


def run_rubble(rubble, rung, n, workdir, threads, end_time=None, measure_it=True):
    """rubble's Sedov scene at n^3 particles as one process under /usr/bin/time."""
    wd = Path(workdir)
    wd.mkdir(parents=True, exist_ok=True)
    dx = 1.0 / n
    sets = [f"bodies.0.spacing={dx!r}", f"energy_deposits.0.radius={4.8 * dx!r}", "output.interval=0",
            f"simulation.h_tolerance={TOLH!r}"]
    if end_time is not None:
        sets.append(f"simulation.end_time={end_time!r}")
    out = wd / "out"
    cmd = ["/usr/bin/time", "-v", "-o", str(wd / "time.log"), str(rubble), "run", str(SCENE), "--out", str(out)]
    for s in sets:
        cmd += ["--set", s]
    if out.exists():
        for f in out.iterdir():
            f.unlink()
        out.rmdir()
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    (wd / "run.log").write_text(res.stdout + res.stderr)
    if res.returncode != 0:
        raise RuntimeError(f"rubble failed ({res.returncode}); see {wd / 'run.log'}")
    m = re.search(r"done: t = (\S+) s after (\d+) steps", res.stderr + res.stdout)
    steps, t_end = int(m.group(2)), float(m.group(1))
    npart = n ** 3
    result = {"code": "rubble", "npart": npart, "steps": steps, "t_end": t_end, "wall_s": wall,
              "peak_rss_kb": peak_rss_kb(wd / "time.log"), "threads": threads}
    if measure_it:
        import h5py
        snaps = sorted(out.glob("sedov.*.h5"))
        with h5py.File(snaps[-1], "r") as f:
            x, v = f["x"][...], f["v"][...]
            cols = [x[:, 0], x[:, 1], x[:, 2], v[:, 0], v[:, 1], v[:, 2], f["m"][...], f["rho"][...], f["u"][...]]
            t = float(f.attrs["time"]) if "time" in f.attrs else t_end
        result["measures"] = measure(rung, cols, t, wd / "particles.txt")
    return result


def run_phantom(phantom, paths, npartx, workdir, threads, tmax=None, nmax=None, rung=None):
    r = phantom.run_sedov(paths, workdir, npartx, tmax=tmax, nmax=nmax, threads=threads)
    if r["returncode"] != 0:
        raise RuntimeError(f"Phantom failed; see {r['logs']['run']}")
    result = {"code": "phantom", "npart": r["npart"], "steps": r["nsteps"], "t_end": r["t_end"],
              "wall_s": r["wall_total_s"], "peak_rss_kb": r["peak_rss_kb"], "threads": threads,
              "phantom_step_wall_s": r["phantom_step_wall_s"]}
    if rung is not None:
        d = phantom.read_dump(r["dump"])
        m = np.broadcast_to(np.asarray(d["m"], dtype=float), d["x"].shape)  # one mass for all, or per particle
        cols = [d["x"], d["y"], d["z"], d["vx"], d["vy"], d["vz"], m, d["rho"], d["u"]]
        result["measures"] = measure(rung, cols, d["time"], Path(workdir) / "particles.txt")
    return result


def median_run(rs):
    """The run of median wall time (the lower middle one for an even count)."""
    ordered = sorted(rs, key=lambda r: r["wall_s"])
    return ordered[(len(ordered) - 1) // 2]


def rate(r):
    return r["npart"] * r["steps"] / r["wall_s"]


def rubble_is_native(build_dir):
    """RUBBLE_NATIVE of a CMake build folder (None if it has no cache to read)."""
    cache = build_dir / "CMakeCache.txt"
    if not cache.is_file():
        return None
    m = re.search(r"^RUBBLE_NATIVE:BOOL=(\S+)", cache.read_text(), re.M)
    return bool(m) and m.group(1).upper() in ("ON", "1", "TRUE", "YES")


def table(small, large):
    lines = ["| case | code | particles | steps | t_end | wall [s] | particle-steps/s | peak RSS [MiB] | "
             "bytes/particle | shock radius | error vs exact |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, pair in (("~1.7e5 to t = 0.1", small), ("~1.4e6, >= 10 steps", large)):
        if not pair:
            continue
        for r in pair:
            if r is None:
                continue
            m = r.get("measures")
            lines.append(
                f"| {name} | {r['code']} | {r['npart']:,} | {r['steps']} | {r['t_end']:.4g} | {r['wall_s']:.1f} | "
                f"{rate(r):.3g} | {r['peak_rss_kb'] / 1024:.0f} | {r['peak_rss_kb'] * 1024 / r['npart']:.0f} | "
                + (f"{m['shock_radius']:.4f} | {100 * m['shock_radius_error']:.2f} % |" if m else "– | – |"))
    lines.append("")
    for name, pair in (("~1.7e5 to t = 0.1", small), ("~1.4e6", large)):
        if pair and all(pair):
            rb, ph = pair
            lines.append(f"- {name}: rubble/Phantom particle-steps per second = {rate(rb) / rate(ph):.2f}; "
                         f"Phantom/rubble wall time = {ph['wall_s'] / rb['wall_s']:.2f}; "
                         f"rubble/Phantom steps = {rb['steps'] / ph['steps']:.2f}; "
                         f"rubble/Phantom memory per particle = "
                         f"{(rb['peak_rss_kb'] / rb['npart']) / (ph['peak_rss_kb'] / ph['npart']):.2f}")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--small", type=parse_pair, default=(56, 50), help="rubble N : Phantom npartx")
    ap.add_argument("--large", type=parse_pair, default=(112, 100), help="rubble N : Phantom npartx")
    ap.add_argument("--large-steps", type=int, default=10)
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--repeat", type=int, default=1,
                    help="run the ~1.7e5 case this many times, the two codes alternating; the table shows each "
                         "code's run of median wall time, and every pair's speed ratio is listed (the machine's "
                         "noise: docs/performance.md)")
    ap.add_argument("--rubble-only", action="store_true", help="run rubble's half only")
    ap.add_argument("--native", action="store_true",
                    help="both codes compiled for this machine's processor: Phantom with -march=native (its own "
                         "build folder), rubble from a build configured with -DRUBBLE_NATIVE=ON (default folder "
                         "build-native); docs/performance.md")
    ap.add_argument("--build", default=None, help="rubble's build folder (default build, or build-native with --native)")
    ap.add_argument("--out", default=str(REPO / "build" / "peers"))
    a = ap.parse_args()
    if a.repeat < 1:
        ap.error("--repeat must be at least 1")

    if a.build is None:
        a.build = str(REPO / ("build-native" if a.native else "build"))
    # The comparison is only matched if both codes were compiled alike.
    native_build = rubble_is_native(Path(a.build))
    if native_build is not None and native_build != a.native:
        sys.exit(f"sedov_vs_phantom: {a.build} was configured with RUBBLE_NATIVE={'ON' if native_build else 'OFF'}, "
                 f"but Phantom would be built {'with' if a.native else 'without'} -march=native; "
                 + ("configure it with -DRUBBLE_NATIVE=ON" if a.native else "pass --native or another --build"))
    rubble = Path(a.build) / "rubble"
    rung = Path(a.build) / "verification" / "sedov_taylor" / "sedov_rung"
    for p in (rubble, rung):
        if not p.exists():
            sys.exit(f"sedov_vs_phantom: {p} not found; build rubble first (cmake --preset ci && cmake --build build)")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    phantom = paths = None
    if not a.rubble_only:
        import phantom as phantom_mod
        src = phantom_mod.DEFAULT_SRC
        built = phantom_mod.DEFAULT_BUILD_NATIVE if a.native else phantom_mod.DEFAULT_BUILD
        if not (src / "src").exists() and not (built / "bin" / "phantom").exists():
            print(f"sedov_vs_phantom: Phantom's source is not in {src} (README.md says how to get it); "
                  "running rubble's half only", file=sys.stderr)
        else:
            phantom = phantom_mod
            paths = phantom.build(native=a.native)

    (nr, npx), (nr_l, npx_l) = a.small, a.large
    runs = []  # (rubble, Phantom or None) per repetition, one after the other
    for _ in range(a.repeat):
        rb = run_rubble(rubble, rung, nr, out / f"rubble_{nr}", a.threads)
        print(json.dumps(rb), flush=True)
        ph = None
        if phantom:
            ph = run_phantom(phantom, paths, npx, out / f"phantom_{npx}", a.threads, tmax=0.1, rung=rung)
            print(json.dumps(ph), flush=True)
        runs.append((rb, ph))
    small = [median_run([r[0] for r in runs]), median_run([r[1] for r in runs if r[1]]) if phantom else None]
    large = None
    if not a.skip_large:
        ph = None
        t_large = None
        if phantom:
            ph = run_phantom(phantom, paths, npx_l, out / f"phantom_{npx_l}", a.threads, nmax=a.large_steps)
            print(json.dumps(ph), flush=True)
            t_large = ph["t_end"]
        rb = run_rubble(rubble, rung, nr_l, out / f"rubble_{nr_l}", a.threads,
                        end_time=t_large if t_large else 0.0137, measure_it=False)
        print(json.dumps(rb), flush=True)
        large = [rb, ph]
    text = table(small, large)
    if a.repeat > 1 and phantom:
        ratios = [rate(rb) / rate(ph) for rb, ph in runs]
        text += ("\n- ~1.7e5, each of the " + str(a.repeat) + " pairs of runs: rubble/Phantom particle-steps per "
                 "second = " + ", ".join(f"{q:.2f}" for q in ratios) + f"; median {statistics.median(ratios):.2f}")
    print(text)
    command = f"python3 benchmarks/peers/sedov_vs_phantom.py --threads {a.threads}"
    if a.native:
        command += " --native"
    if a.repeat > 1:
        command += f" --repeat {a.repeat}"
    (out / "sedov_vs_phantom.md").write_text(f"Command: {command}\n\n" + text + "\n")
    (out / "sedov_vs_phantom.json").write_text(
        json.dumps({"small": small, "large": large, "small_runs": runs}, indent=1))


if __name__ == "__main__":
    main()
