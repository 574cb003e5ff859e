"""Shared steps of the measured experiments: the simulated dataset and CLI calls.

The dataset: every mesh of the table-top library (real sizes; the shrunk kit meshes are rescaled
by the simulator) and procedural objects, each scanned by the simulated Kinect from a few turntable
views, features extracted per object and view with `multicue dataset extract`, labels flattened to
the six categories. Rows of one mesh (or one procedural instance) share a group, so splits by group
never put the same mesh into training and test.
"""

import json
import os
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MULTICUE = os.environ.get("MULTICUE", os.path.join(REPO, "build", "multicue"))
WORK = os.environ.get("WORK", "/tmp/multicue-experiments")


def data_dir():
    """$MULTICUE_DATA, else the MULTICUE_SHARED_DATA_DIR the build beside MULTICUE was configured
    with, else the default of that cache variable (the shared data folder beside the repository)."""
    if os.environ.get("MULTICUE_DATA"):
        return os.environ["MULTICUE_DATA"]
    cache = os.path.join(os.path.dirname(os.path.abspath(MULTICUE)), "CMakeCache.txt")
    if os.path.exists(cache):
        with open(cache) as f:
            for line in f:
                if line.startswith("MULTICUE_SHARED_DATA_DIR:"):
                    return line.split("=", 1)[1].strip()
    return os.path.join(os.path.dirname(REPO), "shared", "data")


MESHES = os.environ.get("MESHES", os.path.join(data_dir(), "meshes", "tabletop"))
JOBS = os.environ.get("JOBS", "2")
VIEWS = os.environ.get("VIEWS", "3")
PROCEDURAL = os.environ.get("PROCEDURAL", "60")
FEATURES = "vfh,grsd-minus,grsd,pfh,fpfh,rsd,part-stats,colour"
VOXEL = "0.006"


def run(*args, capture=False):
    cmd = [MULTICUE, "-j", JOBS] + [str(a) for a in args]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stdout}{r.stderr}")
    return r.stdout if capture else None


def run_json(*args):
    return json.loads(run(*args, "--json", capture=True))


def path(name):
    return os.path.join(WORK, name)


def dataset():
    """WORK/all.mcd: all rows with the six categories as labels (built once, then reused)."""
    os.makedirs(WORK, exist_ok=True)
    out = path("all.mcd")
    if os.path.exists(out):
        return out
    t0 = time.time()
    parts = []
    for name, extra in (("mesh", ["--meshes", MESHES, "--seed", "11"]),
                        ("proc", ["--count", PROCEDURAL, "--seed", "12"])):
        sim = path("sim_" + name)
        if not os.path.exists(os.path.join(sim, "manifest.json")):
            run("simulate", "objects", "--views", VIEWS, "--out", sim, "-q", *extra)
        run("dataset", "extract", "--manifest", os.path.join(sim, "manifest.json"),
            "--features", FEATURES, "--voxel", VOXEL, "-o", path(name + ".mcd"), "--resume", "-q")
        parts.append(path(name + ".mcd"))
    run("dataset", "concat", *parts, "--rows", "-o", path("both.mcd"))
    run("dataset", "relabel", path("both.mcd"), "--depth", "1", "-o", out)
    print(f"dataset: {time.time() - t0:.0f} s", file=sys.stderr)
    return out
