#!/usr/bin/env python3
"""What a feature costs when a scene uses it, and that it costs nothing when
it does not (issue #14 item 5).

    python3 benchmarks/features.py [--build build] [--spacing 0.1] [--threads 2]

One 3-D scene, a basalt sphere of radius 2 m (Tillotson, continuity
density, leapfrog; about 33,000 particles at the default spacing), run for
about 20 steps in these variants:

    hydro                  shear modulus 0
    strength               shear modulus 22.7 GPa (Benz & Asphaug 1999's basalt)
    strength + art. stress the same with [materials.rock.artificial_stress]
    strength + kernel corr the same with simulation.kernel_correction = true
    hydro + self-gravity   [gravity] mode = "barnes_hut"
    strength + self-grav.  both

For each: wall time per step (the steps' time from `rubble run --timings`,
set-up and output excluded), its split into neighbour search, density,
EOS, forces and the rest, and the fields the run allocated (read back from
the final snapshot: its datasets plus those of its restart group, which
holds every allocated field the snapshot proper leaves out). About a
minute on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import tempfile
from pathlib import Path

import h5py

REPO = Path(__file__).resolve().parents[1]

BASE = """
[simulation]
dimension = 3
end_time = {end_time}
integrator = "leapfrog"
density = "continuity"
{simulation_extra}

[materials.rock]
library = "basalt"
shear_modulus = {shear}
{material_extra}

[[bodies]]
shape = "sphere"
material = "rock"
center = [0.0, 0.0, 0.0]
radius = 2.0
spacing = {spacing}
density = 2700.0
internal_energy = 0.0

[output]
name = "features"
interval = 0
{gravity}
"""

VARIANTS = [
    ("hydro", dict(shear=0.0)),
    ("strength", dict(shear=2.27e10)),
    ("strength + artificial stress", dict(shear=2.27e10, material_extra="artificial_stress = { epsilon = 0.3 }")),
    ("strength + kernel correction", dict(shear=2.27e10, simulation_extra="kernel_correction = true")),
    ("hydro + self-gravity", dict(shear=0.0, gravity='[gravity]\nmode = "barnes_hut"')),
    ("strength + self-gravity", dict(shear=2.27e10, gravity='[gravity]\nmode = "barnes_hut"')),
]

STEP_PHASES = ("neighbour search", "density and h", "EOS", "forces", "end of step", "integration",
               "sort", "time-step limit", "state checks")


def fields_of(snapshot):
    with h5py.File(snapshot, "r") as f:
        names = {k for k in f.keys() if isinstance(f[k], h5py.Dataset)}
        if "restart" in f:
            names |= {k for k in f["restart"].keys() if isinstance(f["restart"][k], h5py.Dataset)}
    return names


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=str(REPO / "build"))
    ap.add_argument("--spacing", type=float, default=0.1)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    rubble = Path(a.build) / "rubble"
    # ~20 steps: the Courant step of basalt at this spacing is ~ 0.3 (1.2 dx) / 3.4 km/s
    end_time = 20 * 0.3 * 1.2 * a.spacing / 3.4e3
    env = dict(os.environ, OMP_NUM_THREADS=str(a.threads),
               RUBBLE_MATERIALS=str(REPO / "reference_data" / "materials"))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, v in VARIANTS:
            text = BASE.format(end_time=repr(end_time), spacing=repr(a.spacing), shear=repr(v["shear"]),
                               simulation_extra=v.get("simulation_extra", ""),
                               material_extra=v.get("material_extra", ""), gravity=v.get("gravity", ""))
            scene = Path(tmp) / (re.sub(r"\W+", "_", name) + ".toml")
            scene.write_text(text)
            out = Path(tmp) / (scene.stem + "_out")
            res = subprocess.run([str(rubble), "run", str(scene), "--out", str(out), "--timings", "--quiet"],
                                 capture_output=True, text=True, env=env)
            if res.returncode != 0:
                raise SystemExit(f"{name}: rubble failed:\n{res.stderr}")
            phases = dict((m.group(1).strip(), float(m.group(2)))
                          for m in re.finditer(r"^  (.+?)\s+([0-9.]+)\s+[0-9.]+ %$", res.stdout, re.M))
            snaps = sorted(out.glob("features.*.h5"))
            with h5py.File(snaps[-1], "r") as f:
                steps = int(f.attrs["step"])
                n = int(f["m"].shape[0])
            step_time = sum(phases.get(p, 0.0) for p in STEP_PHASES)
            rows.append((name, n, steps, step_time / steps, phases, sorted(fields_of(snaps[-1]))))

    base = rows[0][3]
    print("| variant | particles | steps | ms per step | vs hydro | neighbours | density | EOS | forces | "
          "rest | fields allocated |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, n, steps, per_step, ph, fields in rows:
        share = {k: 1e3 * ph.get(k, 0.0) / steps for k in ("neighbour search", "density and h", "EOS", "forces")}
        rest = 1e3 * per_step - sum(share.values())
        print(f"| {name} | {n:,} | {steps} | {1e3 * per_step:.1f} | {per_step / base:.2f} | "
              f"{share['neighbour search']:.1f} | {share['density and h']:.1f} | {share['EOS']:.1f} | "
              f"{share['forces']:.1f} | {rest:.1f} | {', '.join(fields)} |")
    print("\n(ms per step of each phase; forces include self-gravity; 'rest' is sort, time-step limit, "
          "state checks, end of step and integration)")


if __name__ == "__main__":
    main()
