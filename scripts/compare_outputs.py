#!/usr/bin/env python3
"""Checks that two multicue builds produce the same outputs.

Runs `multicue perceive` of both binaries on the same frames with the same configurations and
compares result.json (with the measured times removed), labels.pcd and models.ply byte for byte;
also the demo (`multicue demo --no-report`: its scene.pcd and outputs) and, for the part-graph
configurations, the default model each binary trains (`multicue train`, compared byte for byte,
then used by that binary's perceive).

    scripts/compare_outputs.py BEFORE/multicue AFTER/multicue [--frames DIR] [--work DIR]

--frames defaults to ../shared/data/scans/mosd-learn beside the repository (every *.pcd in it).
Exit status 0 when everything is identical, 1 when something differs (each difference is
listed), 2 for bad arguments.
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile

# The keys used here mean the same in every release.
CONFIGS = {
    "default": {},
    "three-experts": {"category": {"categoriser": "part-graph+rules+cluster"}},
    "part-graph": {"category": {"categoriser": "part-graph"}},
    "part-graph+rules": {"category": {"categoriser": "part-graph+rules"}},
    "guided-fits": {"models": {"guided_fits": True}},
}


def normalised_result(path):
    """result.json without the measured times (their keys, the stage names, are kept)."""
    data = json.loads(path.read_text())
    times = data.get("timings_ms")
    if isinstance(times, dict):
        data["timings_ms"] = {k: 0 for k in times}
    return json.dumps(data, sort_keys=True)


def compare_dirs(a, b, names):
    problems = []
    for name in names:
        fa, fb = a / name, b / name
        if not fa.exists() or not fb.exists():
            problems.append(f"{name}: missing ({fa.exists()}, {fb.exists()})")
        elif name == "result.json":
            if normalised_result(fa) != normalised_result(fb):
                problems.append(f"{name}: contents differ")
        elif fa.read_bytes() != fb.read_bytes():
            problems.append(f"{name}: bytes differ")
    return problems


def run(cmd, env, cwd=None):
    r = subprocess.run(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} exited {r.returncode}: {r.stdout.strip()}")


def main():
    root = pathlib.Path(__file__).resolve().parent.parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("before", type=pathlib.Path)
    ap.add_argument("after", type=pathlib.Path)
    ap.add_argument("--frames", type=pathlib.Path,
                    default=root.parent / "shared" / "data" / "scans" / "mosd-learn")
    ap.add_argument("--work", type=pathlib.Path, default=None,
                    help="folder for the outputs (default: a temporary one, removed afterwards)")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--configs", default=",".join(CONFIGS),
                    help="comma-separated subset of " + ", ".join(CONFIGS))
    args = ap.parse_args()
    configs = {name: CONFIGS[name] for name in args.configs.split(",") if name}
    unknown = set(args.configs.split(",")) - set(CONFIGS) - {""}
    if unknown:
        print(f"compare_outputs: unknown configuration {', '.join(sorted(unknown))}", file=sys.stderr)
        return 2
    for b in (args.before, args.after):
        if not os.access(b, os.X_OK):
            print(f"compare_outputs: {b}: not an executable", file=sys.stderr)
            return 2
    frames = sorted(args.frames.glob("*.pcd"), key=lambda p: (len(p.stem), p.stem))
    if not frames:
        print(f"compare_outputs: no .pcd frames in {args.frames}", file=sys.stderr)
        return 2

    tmp = None
    if args.work is None:
        tmp = tempfile.TemporaryDirectory(prefix="multicue-compare-")
        work = pathlib.Path(tmp.name)
    else:
        work = args.work
        work.mkdir(parents=True, exist_ok=True)

    problems = []
    sides = {"before": args.before.resolve(), "after": args.after.resolve()}
    envs = {}
    for side, binary in sides.items():
        env = dict(os.environ)
        env["XDG_CACHE_HOME"] = str(work / side / "cache")  # each side trains its own model
        envs[side] = env
        for name, config in configs.items():
            if "category" in config:  # the model this side trains below
                config = dict(config, category=dict(
                    config["category"], part_graph_model=str(work / side / "default.mcpg")))
            (work / side).mkdir(parents=True, exist_ok=True)
            (work / side / f"{name}.json").write_text(json.dumps(config))

    outputs = ["result.json", "labels.pcd", "models.ply"]
    threads = ["--threads", str(args.threads)]
    # The default part-graph model each side trains (and caches for its perceive runs).
    for side, binary in (sides.items() if any("category" in c for c in configs.values()) else []):
        print(f"[{side}] training the default part-graph model", flush=True)
        run([binary, *threads, "--log-level", "warning", "train", "--out",
             work / side / "default.mcpg"], envs[side])
    a, b = work / "before" / "default.mcpg", work / "after" / "default.mcpg"
    if a.exists() and a.read_bytes() != b.read_bytes():
        problems.append("default part-graph model: bytes differ")

    checked = 0
    for name in configs:
        for frame in frames:
            dirs = {}
            for side, binary in sides.items():
                out = work / side / name / frame.stem
                cmd = [binary, *threads, "perceive", frame, "--out", out, "-q", "--no-report",
                       "--config", work / side / f"{name}.json"]
                run(cmd, envs[side])
                dirs[side] = out
            for p in compare_dirs(dirs["before"], dirs["after"], outputs):
                problems.append(f"{name} {frame.name}: {p}")
            checked += 1
        print(f"{name}: {len(frames)} frames compared", flush=True)

    # Several registered views of simulated scenes (perceive --manifest: categories fused over
    # the frames, changed objects modelled again).
    for side, binary in sides.items():
        run([binary, *threads, "simulate", "scenes", "--out", "views", "--scenes", "2",
             "--views", "3", "--objects", "4,6", "--seed", "3", "-q"], envs[side], work / side)
    for scene in (0, 1):
        for name in [n for n in ("default", "three-experts") if n in configs]:
            for side, binary in sides.items():
                run([binary, *threads, "perceive", "--manifest", "views/manifest.json", "--scene",
                     str(scene), "--out", f"views-{name}-{scene}", "-q", "--no-report", "--config",
                     work / side / f"{name}.json"], envs[side], work / side)
            for frame in sorted((work / "before" / f"views-{name}-{scene}").iterdir()):
                other = work / "after" / f"views-{name}-{scene}" / frame.name
                for p in compare_dirs(frame, other, outputs):
                    problems.append(f"views {name} scene {scene} {frame.name}: {p}")
                checked += 1

    for side, binary in sides.items():
        # A relative folder: result.json names the input file, the same on both sides.
        run([binary, *threads, "demo", "--out", "demo", "--no-report"], envs[side], work / side)
    for p in compare_dirs(work / "before" / "demo", work / "after" / "demo",
                          ["scene.pcd", *outputs]):
        problems.append(f"demo: {p}")
    checked += 1

    for p in problems:
        print(p)
    print(f"{checked} runs compared per side, {len(problems)} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
