#!/usr/bin/env python3
"""Peak memory (resident set) of `multicue perceive` against the size of its input.

    scripts/perceive_memory.py [--cli build/multicue] [--data ../shared/data] [--points 10000000]

Runs perceive (no report page) under /usr/bin/time on
  * a 640x480 frame: the shared Kinect scan table_scene_mug_stereo_textured.pcd when the data
    folder is there, else a simulated Kinect frame (`multicue simulate scenes`);
  * a synthetic unorganized table-top scene of --points points (x y z, binary PCD): a table top
    with boxes on it and a floor below, written by this script;
  * a 397-point cloud, for the program's own footprint (code, libraries, thread pools).
and prints, per input, its size (points x bytes per point of the fields it has), the peak RSS
and the peak RSS above the small cloud's, each as a multiple of the input size.
"""

import argparse
import array
import random
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def synthetic_scene(path, n, seed=1):
    """Unorganized camera-frame cloud (y down, z forward): floor, table top, boxes on it."""
    rng = random.Random(seed)
    xyz = array.array("f")
    boxes = [(-0.3, 1.3, 0.12, 0.2, 0.1), (0.0, 1.5, 0.1, 0.1, 0.25), (0.25, 1.2, 0.15, 0.08, 0.12),
             (0.3, 1.7, 0.06, 0.06, 0.3), (-0.2, 1.75, 0.2, 0.15, 0.05)]
    table_y = 0.6  # table top 0.6 m below the camera
    u = rng.random
    for i in range(n):
        r = u()
        if r < 0.5:  # table top 1.2 x 0.9 m
            x, y, z = -0.6 + 1.2 * u(), table_y + rng.gauss(0.0, 0.002), 1.05 + 0.9 * u()
        elif r < 0.65:  # floor
            x, y, z = -2.0 + 4.0 * u(), 1.35 + rng.gauss(0.0, 0.003), 0.5 + 3.0 * u()
        else:  # a face of a box: top or one of the four sides
            cx, cz, sx, sz, h = boxes[i % len(boxes)]
            face = rng.randrange(5)
            a, b = u() - 0.5, u()
            if face == 0:
                x, y, z = cx + sx * a, table_y - h, cz + sz * (b - 0.5)
            elif face < 3:
                x, y, z = cx + sx * (0.5 if face == 1 else -0.5), table_y - h * b, cz + sz * a
            else:
                x, y, z = cx + sx * a, table_y - h * b, cz + sz * (0.5 if face == 3 else -0.5)
        xyz.extend((x, y, z))
    header = (f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\n"
              f"HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        xyz.tofile(f)


def pcd_point_bytes(cli, path):
    """Points and bytes per point of the fields a cloud has (as `multicue info` lists them)."""
    info = subprocess.run([str(cli), "info", str(path)], check=True, capture_output=True,
                          text=True).stdout
    points = int(re.search(r"points:\s+(\d+)", info).group(1))
    fields = re.search(r"fields:\s+(.*)", info).group(1).split()
    sizes = {"x": 4, "y": 4, "z": 4, "rgb": 4, "rgba": 4, "label": 4, "normal_x": 4,
             "normal_y": 4, "normal_z": 4, "curvature": 4, "intensity": 4, "category": 1,
             "part": 2}
    return points, sum(sizes.get(f, 4) for f in fields)


def peak_rss_mb(cli, cloud, out):
    r = subprocess.run(["/usr/bin/time", "-v", str(cli), "perceive", str(cloud), "--out", str(out),
                        "--no-report", "-q"], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"perceive failed on {cloud}: {r.stderr.strip()}")
    kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr).group(1))
    seconds = re.search(r"Elapsed \(wall clock\) time .*: (.*)", r.stderr).group(1)
    return kb / 1024.0, seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", default=ROOT / "build" / "multicue")
    ap.add_argument("--data", default=ROOT.parent / "shared" / "data")
    ap.add_argument("--points", type=int, default=10_000_000)
    args = ap.parse_args()
    cli, data = Path(args.cli), Path(args.data)
    tmp = Path(tempfile.mkdtemp(prefix="multicue-memory-"))
    try:
        small = tmp / "small.pcd"
        synthetic_scene(small, 397)
        frame = data / "scans" / "table_scene_mug_stereo_textured.pcd"
        if not frame.is_file():
            subprocess.run([str(cli), "simulate", "scenes", "--scenes", "1", "--out",
                            str(tmp / "sim"), "-q"], check=True)
            frame = tmp / "sim" / "scene_0000_view_00.pcd"
        big = tmp / "synthetic.pcd"
        synthetic_scene(big, args.points)
        base, _ = peak_rss_mb(cli, small, tmp / "out-small")
        print(f"program footprint (perceive on 397 points): {base:.0f} MB peak RSS\n")
        print("| input | points | input size [MB] | peak RSS [MB] | x input | above footprint "
              "[MB] | x input | wall time |")
        print("|---|---|---|---|---|---|---|---|")
        for name, cloud in [(frame.name, frame), (f"synthetic {args.points} points", big)]:
            points, bpp = pcd_point_bytes(cli, cloud)
            size = points * bpp / 2**20
            rss, wall = peak_rss_mb(cli, cloud, tmp / "out")
            print(f"| {name} | {points} | {size:.1f} | {rss:.0f} | {rss / size:.1f} | "
                  f"{rss - base:.0f} | {(rss - base) / size:.1f} | {wall} |")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
