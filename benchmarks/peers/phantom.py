#!/usr/bin/env python3
"""Run Phantom's 3-D Sedov blast wave as a peer benchmark for rubble.

Phantom (Price et al. 2018, https://github.com/danieljprice/phantom) is a
public Fortran SPH code. This module builds it for its ``sedov`` setup, runs
the setup and the simulation non-interactively, measures wall time, peak
memory and steps, and reads the final dump into numpy arrays. Phantom's code
is never committed: it lives in the git-ignored ``.deps/phantom/`` (see
README.md in this folder).

API (see the docstrings):
    build(phantom_src_dir, build_dir)          -> dict of paths
    run_sedov(paths, workdir, npartx, tmax=None, nmax=None, threads=2, ...)
                                               -> dict of measurements
    read_dump(path)                            -> dict of numpy arrays

Command line: ``python phantom.py --npartx 16 [--tmax 0.1] [--nmax 10]``
builds if needed, runs, and prints the result dict as JSON.

What the Phantom run is set to, and why (to match rubble's Sedov rung):
  * kernel: M4 cubic spline. It is the Makefile's default (KERNEL unset ->
    kernel_cubic.f90); the sedov SETUP does not change it.
  * hfact = 1.2 (Phantom's default for the cubic kernel, h = hfact (m/rho)^1/3).
  * artificial viscosity: Phantom by default uses the Cullen & Dehnen (2010)
    switch with alpha in [alpha, alphamax] = [0, 1], beta = 2. With
    viscosity="fixed" (the default here) we set alpha = alphamax = 1, which
    pins every particle's alpha at 1 (the switch's lower and upper bounds
    coincide): the classic Monaghan (1992) alpha = 1, beta = 2 like rubble.
    viscosity="switch" keeps Phantom's defaults.
  * artificial conductivity alphau = 1 (Price 2008; the sedov setup sets it,
    and it is also the general default).
  * global time steps: built with IND_TIMESTEPS=no (the sedov SETUP block
    in build/Makefile_setups sets IND_TIMESTEPS=yes; a command-line make
    variable overrides it).
  * C_cour = 0.3, C_force = 0.25 (Phantom's defaults, written explicitly).
  * tolh = TOLH = 1e-4, the relative tolerance of the h-rho iteration
    (Phantom's default, written explicitly; rubble's matching key is
    simulation.h_tolerance, which sedov_vs_phantom.py sets to the same).
  * dtmax = tmax and nfulldump = 1, so the only dumps are the t = 0 one and
    a full dump at the end (tmax or nmax steps); dtmax also caps the step
    and Phantom shortens the last step to land on tmax exactly.
  * OpenMP with OMP_NUM_THREADS=threads, OMP_SCHEDULE=dynamic and a large
    OMP_STACKSIZE, as Phantom's own docs recommend.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shlex
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
DEFAULT_SRC = REPO / ".deps" / "phantom" / "src"           # a clone / archive of Phantom
DEFAULT_BUILD = REPO / ".deps" / "phantom" / "build-sedov"

# Make variables (read from build/Makefile, Makefile_setups, Makefile_systems):
#   SETUP=sedov        -> PERIODIC=yes, SETUPFILE=setup_sedov.f90
#   SYSTEM=gfortran    -> Makefile_defaults_gfortran: -O3 -funroll-loops ... -fopenmp
#   IND_TIMESTEPS=no   -> no -DIND_TIMESTEPS, i.e. global time steps
#   OPENMP=yes         -> the Makefile's default, stated for clarity
# DOUBLEPRECISION defaults to yes (-fdefault-real-8) and KERNEL to cubic.
MAKE_VARS = {"SETUP": "sedov", "SYSTEM": "gfortran", "IND_TIMESTEPS": "no", "OPENMP": "yes"}


# --------------------------------------------------------------------------
# build
# --------------------------------------------------------------------------
# Relative tolerance of the h-rho iteration, Phantom's default tolh (its
# sedov.in); rubble runs with simulation.h_tolerance at the same value.
TOLH = 1e-4

DEFAULT_BUILD_NATIVE = REPO / ".deps" / "phantom" / "build-sedov-native"

# For a build compiled for this machine's processor (the counterpart of
# rubble's -DRUBBLE_NATIVE=ON): the compiler command itself carries the flag,
# so that every compile and link line of Phantom's Makefile gets it and none
# of its own FFLAGS (-O3 -funroll-loops ...) is replaced.
NATIVE_FC = "gfortran -march=native"


def build(phantom_src_dir=DEFAULT_SRC, build_dir=None, jobs=1, force=False, native=False):
    """Build ``phantom`` and ``phantomsetup`` for the sedov setup.

    native: compile with ``-march=native`` (``FC="gfortran -march=native"``)
    in a build folder of its own (default .deps/phantom/build-sedov-native).

    Phantom's Makefile builds in ``<tree>/build`` and puts binaries in
    ``<tree>/bin``, and config.F90 includes ``../../build/phantom-version.h``
    relative to itself, so an out-of-tree build needs its own copy of the
    tree: ``src/``, ``build/`` and ``scripts/`` are copied (about 9 MB) into
    ``build_dir`` and make runs there. The copy is not refreshed if the
    source changes; pass force=True to start again.

    Returns {"phantom", "phantomsetup", "build_dir", "commands", "log"}.
    """
    if build_dir is None:
        build_dir = DEFAULT_BUILD_NATIVE if native else DEFAULT_BUILD
    src = Path(phantom_src_dir).resolve()
    bdir = Path(build_dir).resolve()
    bindir = bdir / "bin"
    paths = {
        "phantom": str(bindir / "phantom"),
        "phantomsetup": str(bindir / "phantomsetup"),
        "build_dir": str(bdir),
        "log": str(bdir / "make.log"),
    }
    make_args = [f"{k}={v}" for k, v in MAKE_VARS.items()]
    if native:
        make_args.append(f"FC={NATIVE_FC}")
    cmds = [["make", f"-j{jobs}", *make_args, target] for target in ("phantom", "setup")]
    paths["commands"] = [f"cd {bdir / 'build'} && " + " ".join(shlex.quote(w) for w in c) for c in cmds]
    if not force and all(Path(paths[k]).is_file() for k in ("phantom", "phantomsetup")):
        return paths

    if not (src / "build" / "Makefile").is_file():
        raise FileNotFoundError(f"{src} does not look like a Phantom source tree (no build/Makefile)")
    if force and bdir.exists():
        shutil.rmtree(bdir)
    bindir.mkdir(parents=True, exist_ok=True)
    for sub in ("src", "build", "scripts"):
        if not (bdir / sub).exists():
            shutil.copytree(src / sub, bdir / sub, symlinks=True)

    # scripts/phantom_version_gen.sh calls git; point it at Phantom's own
    # repository if there is one, never at an enclosing repository (rubble's).
    env = dict(os.environ)
    if (src / ".git").exists():
        env.update(GIT_DIR=str(src / ".git"), GIT_WORK_TREE=str(src))
    else:
        env["GIT_DIR"] = str(bdir / "no-git")
    with open(paths["log"], "w") as log:
        for c in cmds:
            log.write("$ " + " ".join(c) + "\n")
            log.flush()
            r = subprocess.run(c, cwd=bdir / "build", env=env, stdout=log, stderr=subprocess.STDOUT)
            if r.returncode != 0:
                raise RuntimeError(f"Phantom build failed ({' '.join(c)}); see {paths['log']}")
    return paths


# --------------------------------------------------------------------------
# run
# --------------------------------------------------------------------------
def _set_in_options(infile, options):
    """Set ``key = value`` lines in a Phantom .in file, appending missing keys.

    Phantom reads the file by key name (infile_utils), so keeping the
    column layout is cosmetic; we still keep the comment after the value.
    """
    text = Path(infile).read_text()
    for key, value in options.items():
        pat = re.compile(rf"^(\s*{re.escape(key)}\s*=\s*)(\S+)(.*)$", re.M)
        if pat.search(text):
            text = pat.sub(lambda m: f"{m.group(1)}{value}{m.group(3)}", text, count=1)
        else:
            text += f"{key:>20s} = {value}\n"
    Path(infile).write_text(text)


def _timed(cmd, cwd, env, log_path):
    """Run cmd under /usr/bin/time -v; return (wall seconds, peak RSS kB, rc)."""
    time_path = Path(str(log_path) + ".time")
    t0 = time.perf_counter()
    with open(log_path, "w") as log:
        r = subprocess.run(["/usr/bin/time", "-v", "-o", str(time_path), *cmd],
                           cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT,
                           preexec_fn=_raise_stack_limit)
    wall = time.perf_counter() - t0
    m = re.search(r"Maximum resident set size \(kbytes\):\s*(\d+)", time_path.read_text())
    return wall, int(m.group(1)) if m else None, r.returncode


def _raise_stack_limit():
    # Phantom's docs ask for `ulimit -s unlimited`; raise the soft limit as far as allowed.
    soft, hard = resource.getrlimit(resource.RLIMIT_STACK)
    try:
        resource.setrlimit(resource.RLIMIT_STACK, (hard, hard))
    except (ValueError, OSError):
        pass


def run_sedov(build_paths, workdir, npartx, tmax=None, nmax=None, threads=2,
              viscosity="fixed", lattice=2, extra_options=None):
    """Set up and run Phantom's sedov problem in ``workdir`` (old sedov* files there are removed).

    npartx   : particles along x; the close-packed lattice (Phantom's default,
               lattice=2) gives npartx x ~1.15 npartx x ~1.2 npartx particles:
               16 -> 5,184; 50 -> 174,000; 100 -> 1,368,000.
    tmax     : end time (default 0.1, the setup's own value).
    nmax     : stop after this many steps instead (Phantom's ``nmax`` key;
               -1 = no limit). Either limit ends the run with a full dump.
    threads  : OMP_NUM_THREADS.
    viscosity: "fixed" (alpha = alphamax = 1) or "switch" (Phantom's default
               Cullen-Dehnen switch, alpha from 0 to 1).
    extra_options: further .in keys to set, e.g. {"C_cour": 0.3}.

    Returns a dict: npart, nsteps, t_end, dump (final dump path),
    wall_total_s (setup + run), wall_run_s (the phantom process alone),
    wall_setup_s, phantom_step_wall_s (Phantom's own timer for the time
    stepping, i.e. without start-up and I/O), peak_rss_kb (max of setup and
    run), peak_rss_run_kb, peak_rss_setup_kb, options (.in values set),
    logs, returncode.
    """
    wd = Path(workdir).resolve()
    wd.mkdir(parents=True, exist_ok=True)
    for f in wd.glob("sedov*"):
        f.unlink()
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_SCHEDULE="dynamic", OMP_STACKSIZE="512M")

    # 1. The .setup file phantomsetup would otherwise write with its defaults and then stop.
    (wd / "sedov.setup").write_text(
        "# input file for Sedov Blast Wave setup routine\n\n"
        "# particle resolution & placement\n"
        f"              npartx = {int(npartx)}    ! number of particles in x-direction\n"
        f"             lattice = {int(lattice)}    ! particle lattice (1=cubic,2=closepacked,3=hcp,4=random)\n"
        "       shuffle_parts = F    ! relax particles by shuffling\n")

    # 2. phantomsetup writes sedov_00000.tmp and sedov.in. Without --maxp it
    #    allocates for 5.2e6 particles (about 1.8 GB); size it to the lattice.
    maxp = int(1.5 * npartx**3) + 1000
    wall_setup, rss_setup, rc = _timed([build_paths["phantomsetup"], "sedov", f"--maxp={maxp}"],
                                       wd, env, wd / "setup.log")
    if rc != 0 or not (wd / "sedov.in").is_file():
        raise RuntimeError(f"phantomsetup failed (rc={rc}); see {wd / 'setup.log'}")

    # 3. Runtime options (see the module docstring for why).
    tmax = 0.1 if tmax is None else float(tmax)
    options = {
        "tmax": tmax,
        "dtmax": tmax,          # one dump interval: no extra steps cut short at dump times
        "nmax": -1 if nmax is None else int(nmax),
        "nfulldump": 1,         # every dump (hence the last) is a full dump with v and u
        "C_cour": 0.3,
        "C_force": 0.25,
        "hfact": 1.2,
        "alpha": 1.0 if viscosity == "fixed" else 0.0,
        "alphamax": 1.0,
        "beta": 2.0,
        "alphau": 1.0,
        "tolh": TOLH,
    }
    if viscosity not in ("fixed", "switch"):
        raise ValueError("viscosity must be 'fixed' or 'switch'")
    options.update(extra_options or {})
    _set_in_options(wd / "sedov.in", options)

    # 4. The run (phantom rewrites sedov.in after each full dump; harmless).
    wall_run, rss_run, rc = _timed([build_paths["phantom"], "sedov.in"], wd, env, wd / "run.log")
    log = (wd / "run.log").read_text(errors="replace")
    dumps = re.findall(r"full dump written to file (\S+)", log)
    m_steps = re.findall(r"Since code start:\s*(\d+) timesteps", log)
    m_npart = re.search(r"npart total\s*=\s*(\d+)", log)
    # Timer table rows "├─step : 2.80s 2.82s ..." (one table per dump, each
    # since the previous dump); the wall column is in s, min or h.
    m_step = re.findall(r"─step\s*:\s*([\d.]+)(s|min|h)\b", log)
    m_threads = re.search(r"Running in openMP on\s+(\d+) threads", log)
    t_end = None
    if dumps:
        t_end = float(read_header(wd / dumps[-1])["time"])
    return {
        "npartx": int(npartx),
        "npart": int(m_npart.group(1)) if m_npart else None,
        "threads": int(m_threads.group(1)) if m_threads else None,
        "nsteps": int(m_steps[-1]) if m_steps else None,
        "t_end": t_end,
        "dump": str(wd / dumps[-1]) if dumps else None,
        "wall_total_s": wall_setup + wall_run,
        "wall_setup_s": wall_setup,
        "wall_run_s": wall_run,
        "phantom_step_wall_s": sum(float(x) * {"s": 1, "min": 60, "h": 3600}[u] for x, u in m_step)
                               if m_step else None,
        "peak_rss_kb": max(rss_setup or 0, rss_run or 0),
        "peak_rss_setup_kb": rss_setup,
        "peak_rss_run_kb": rss_run,
        "options": options,
        "logs": {"setup": str(wd / "setup.log"), "run": str(wd / "run.log")},
        "returncode": rc,
    }


# --------------------------------------------------------------------------
# dump reading
# --------------------------------------------------------------------------
# A Phantom dump (docs/dumpfile.rst; the sphNG format) is a Fortran
# unformatted sequential file: every record is framed by 4-byte byte counts.
#   1. i1=060769, r1=real(i2), i2=060878, iversion, i3=690706 (default int, real)
#   2. a 100-character file identifier ("FT:..." = full dump, "ST:" small)
#   3. the header: for each of 8 types (default int, int*1, int*2, int*4,
#      int*8, default real, real*4, real*8): nvars, then 16-char tags, then values
#   4. narraylengths * nblocks (nblocks = MPI writers); then per MPI block,
#      narraylengths records (int*8 n, int*4 nums(8)) giving how many arrays
#      of each of the 8 types follow, then those arrays, each as a tag record
#      and a data record of n values. Array group 2 holds sink particles.
_INT_TYPES = ["<i1", "<i2", "<i4", "<i8"]  # header/array types 2-5; 1 and 6 are the default int/real


class _Reader:
    def __init__(self, path):
        self.buf = Path(path).read_bytes()
        self.pos = 0

    def record(self):
        (n,) = np.frombuffer(self.buf, "<i4", 1, self.pos)
        data = self.buf[self.pos + 4:self.pos + 4 + n]
        (n2,) = np.frombuffer(self.buf, "<i4", 1, self.pos + 4 + n)
        if n != n2:
            raise ValueError("corrupt Fortran record (mismatched markers)")
        self.pos += 8 + n
        return data


def _read_start(r):
    first = r.record()
    for ityp, rtyp in (("<i4", "<f8"), ("<i4", "<f4"), ("<i8", "<f8"), ("<i8", "<f4")):
        isz, rsz = np.dtype(ityp).itemsize, np.dtype(rtyp).itemsize
        if len(first) != 4 * isz + rsz:
            continue
        i1 = np.frombuffer(first, ityp, 1, 0)[0]
        r1 = np.frombuffer(first, rtyp, 1, isz)[0]
        i2 = np.frombuffer(first, ityp, 1, isz + rsz)[0]
        if i1 == 60769 and i2 == 60878 and r1 == i2:
            types = [ityp] + _INT_TYPES + [rtyp, "<f4", "<f8"]
            ident = r.record().decode("ascii", "replace").strip()
            header = {}
            for t in types:
                (nvars,) = np.frombuffer(r.record(), "<i4", 1)
                if nvars > 0:
                    tags = r.record().decode("ascii")
                    vals = np.frombuffer(r.record(), t, nvars)
                    for k in range(nvars):
                        tag = tags[16 * k:16 * k + 16].strip()
                        if tag in header:  # repeated tags (npartoftype, massoftype) become lists
                            prev = header[tag]
                            header[tag] = (prev if isinstance(prev, list) else [prev]) + [vals[k].item()]
                        else:
                            header[tag] = vals[k].item()
            return types, ident, header
    raise ValueError("not a Phantom dump (capture pattern not found; big-endian files are not supported)")


def read_header(path):
    """The dump's header values (time, hfact, massoftype, xmin..zmax, ...)."""
    return _read_start(_Reader(path))[2]


def read_dump(path, backend="native"):
    """Read a Phantom full dump; return numpy arrays and scalars.

    Keys: x, y, z, vx, vy, vz, u, h, rho, m (per-particle arrays, float64),
    time, hfact, npart, box (xmin, xmax, ymin, ymax, zmin, zmax), header
    (all header values) and columns (the names of every array in the file).

    Phantom stores h (as real*4) rather than rho; here
    rho = m (hfact/|h|)^3, exactly what Phantom uses (part.F90: rhoh).
    Particles with h <= 0 (dead/accreted) are dropped.

    backend="native" uses the small reader above (numpy only);
    backend="sarracen" uses the sarracen package (pip install sarracen
    scikit-learn; sarracen imports scikit-learn but does not declare it).
    """
    if backend == "sarracen":
        import sarracen
        sdf = sarracen.read_phantom(str(path), separate_types=None)
        header = dict(sdf.params)
        cols = {c: sdf[c].to_numpy() for c in sdf.columns}
        m = np.full(len(sdf), float(header["massoftype"]))
    else:
        r = _Reader(path)
        types, ident, header = _read_start(r)
        if not ident.startswith("F"):
            raise ValueError(f"{path} is a small dump ({ident[:2]}); it has no velocities or u")
        # First record: narraylengths * nblocks (nblocks = MPI processes that
        # wrote the file). Each MPI block holds narraylengths groups of arrays:
        # 1 = gas (hydro), 2 = sink particles, 3-4 = MHD arrays (gas length).
        (ntotal,) = np.frombuffer(r.record(), "<i4", 1)
        nmpi = int(header.get("nblocks", 1))
        narray = int(ntotal) // nmpi
        cols = {}
        for _ in range(nmpi):
            counts = []
            for _ in range(narray):
                rec = r.record()
                counts.append((int(np.frombuffer(rec, "<i8", 1, 0)[0]), np.frombuffer(rec, "<i4", 8, 8)))
            for j, (n, nums) in enumerate(counts):
                for t, nt in zip(types, nums):
                    for _ in range(nt):
                        tag = r.record().decode("ascii").strip()
                        data = np.frombuffer(r.record(), t, n)
                        if j != 1:  # skip sink particles (none in the sedov setup)
                            cols[tag] = np.concatenate([cols[tag], data]) if tag in cols else data.copy()
        mass = header["massoftype"]
        m = np.full(len(cols["x"]), float(mass[0] if isinstance(mass, list) else mass))
        # Only one particle type (gas) in the sedov setup; a multi-type dump would need itype.
        if "itype" in cols and np.any(cols["itype"] != 1):
            raise NotImplementedError("dump with several particle types")

    h = np.asarray(cols["h"], dtype=np.float64)
    alive = h > 0
    hfact = float(header["hfact"])
    out = {k: np.asarray(cols[k], dtype=np.float64)[alive] for k in ("x", "y", "z", "vx", "vy", "vz", "u")}
    out["h"] = h[alive]
    out["m"] = m[alive]
    out["rho"] = out["m"] * (hfact / out["h"]) ** 3
    out.update(
        time=float(header["time"]),
        hfact=hfact,
        npart=int(alive.sum()),
        box=tuple(float(header[k]) for k in ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")),
        header=header,
        columns=list(cols),
    )
    return out


# --------------------------------------------------------------------------
def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--src", default=str(DEFAULT_SRC), help="Phantom source tree")
    ap.add_argument("--build-dir", default=str(DEFAULT_BUILD))
    ap.add_argument("--workdir", default=str(REPO / "out" / "phantom-sedov"))
    ap.add_argument("--npartx", type=int, default=50)
    ap.add_argument("--tmax", type=float, default=None)
    ap.add_argument("--nmax", type=int, default=None)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--viscosity", choices=("fixed", "switch"), default="fixed")
    a = ap.parse_args()
    paths = build(a.src, a.build_dir)
    res = run_sedov(paths, a.workdir, a.npartx, tmax=a.tmax, nmax=a.nmax,
                    threads=a.threads, viscosity=a.viscosity)
    if res["dump"]:
        d = read_dump(res["dump"])
        res["dump_summary"] = {"npart": d["npart"], "time": d["time"],
                               "rho_max": float(d["rho"].max()),
                               "E_kin": float(0.5 * np.sum(d["m"] * (d["vx"]**2 + d["vy"]**2 + d["vz"]**2))),
                               "E_th": float(np.sum(d["m"] * d["u"]))}
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
