#!/usr/bin/env python3
"""ci/fragments on a run whose fragments are known (issue #18 item 5).

Two blocks of a brittle solid are pulled apart (the damage unit tests' scene):
at t = 0 the friends-of-friends groups are one body of every particle; with
--damage-max 0 every particle is its own fragment; at the end the two halves
are the two largest fragments, moving apart, and masses add up.

    test_fragments.py RUBBLE_BINARY FRAGMENTS_SCRIPT WORKDIR
"""
import csv
import os
import shutil
import subprocess
import sys

SCENE = """[simulation]
dimension = 2
end_time = 1.0
integrator = "leapfrog"
[materials.rock]
eos = "murnaghan"
murnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }
shear_modulus = 0.5
damage = { model = "grady_kipp", weibull_k = 1e20, weibull_m = 6.0 }
[[bodies]]
shape = "box"
material = "rock"
min = [0.0, 0.0]
max = [0.5, 0.4]
spacing = 0.05
density = 1.0
internal_energy = 0.0
velocity = [-0.1, 0.0]
[[bodies]]
shape = "box"
material = "rock"
min = [0.5, 0.0]
max = [1.0, 0.4]
spacing = 0.05
density = 1.0
internal_energy = 0.0
velocity = [0.1, 0.0]
[output]
name = "pull"
interval = 0.25
"""


def table(path):
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    head = rows[0]
    return [dict(zip(head, map(float, r))) for r in rows[1:]]


def main(rubble, script, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    scene = os.path.join(work, "pull.toml")
    with open(scene, "w") as f:
        f.write(SCENE)
    subprocess.run([rubble, "run", scene, "--out", os.path.join(work, "run"), "-q"], check=True)
    snap = lambda k: os.path.join(work, "run", "pull.%04d.h5" % k)
    fails = []

    subprocess.run([sys.executable, script, snap(0), "--out", os.path.join(work, "t0")], check=True)
    t0 = table(os.path.join(work, "t0", "fragments.csv"))
    if len(t0) != 1 or t0[0]["particles"] != 160:
        fails.append("t = 0: expected one fragment of 160 particles, got %d" % len(t0))

    subprocess.run([sys.executable, script, snap(0), "--damage-max", "0", "--out", os.path.join(work, "t0s")], check=True)
    if len(table(os.path.join(work, "t0s", "fragments.csv"))) != 160:
        fails.append("--damage-max 0: expected 160 single-particle fragments")

    subprocess.run([sys.executable, script, snap(4), "--out", os.path.join(work, "t4")], check=True)
    t4 = table(os.path.join(work, "t4", "fragments.csv"))
    total = sum(r["mass"] for r in t4)
    if abs(total - 0.4) > 1e-9:  # 160 particles of 0.0025 kg
        fails.append("masses add up to %g, not 0.4" % total)
    if any(a["mass"] < b["mass"] for a, b in zip(t4, t4[1:])):
        fails.append("the table is not sorted by mass")
    big = t4[:2]
    if len(t4) < 2 or big[1]["particles"] < 40 or big[0]["v_x"] * big[1]["v_x"] >= 0:
        fails.append("the two halves are not the two largest fragments moving apart: %s" % big)
    if not os.path.exists(os.path.join(work, "t4", "fragments.png")):
        fails.append("no plot")
    for f in fails:
        print("FAIL", f)
    print("fragments: %d at the end, largest %d particles" % (len(t4), t4[0]["particles"]))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
