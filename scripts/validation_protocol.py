#!/usr/bin/python3
"""The validation protocol of the table-top pipeline: perceive on every split, scored per scene
type, with PCL's LCCP on the same frames when its driver is built, and the running time of every
frame (median, worst, worst / median).

Splits (see eval/README.md, "Validation protocol"):
  tune      the 45 mOSD learn scenes: the data perceive's defaults were chosen on
  validate  the 11 mOSD test scenes in scans/mosd-validate (mixed, complex): the data design
            choices are checked on; never a test figure
  samples   PCL's sample table scans (no ground truth): objects, categories and model sizes
  sim       simulated scenes of one scene type each (`multicue simulate scenes --mode`) from the
            meshes of one half of the mesh split (`--mesh-split test` for reported figures)

usage: validation_protocol.py [--build build] [--data ../shared/data] [--out DIR]
           [--splits tune,validate,samples] [--peers build-peer/eval/mosd_peers]
           [--config FILE] [--sim-modes complex,mixed] [--sim-scenes 10] [--sim-seed 1000]
           [--sim-objects MIN,MAX] [--mesh-split test]
           [--json FILE]
Needs numpy and scipy (run with /usr/bin/python3) and the shared tools/osd_eval.py scorer.
Exit code 0 when every run finished, 1 when a run failed, 2 on bad arguments.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time

MOSD_GROUPS = {
    "tune": [("boxes", range(0, 17)), ("stacked", range(17, 25)), ("occluded", range(25, 33)),
             ("cylindric", range(33, 45))],
    "validate": [("mixed", range(43, 49)), ("complex", range(55, 60))],
}
SAMPLES = ["table_scene_mug_stereo_textured", "milk_cartoon_all_small_clorox",
           "region_growing_tutorial"]


def fail(msg, code=2):
    print(f"validation_protocol: {msg}", file=sys.stderr)
    sys.exit(code)


def scene_number(name):
    m = re.search(r"(\d+)$", name)
    return int(m.group(1)) if m else -1


def load_scorer(data):
    tools = os.path.join(os.path.dirname(os.path.abspath(data)), "tools")
    if not os.path.exists(os.path.join(tools, "osd_eval.py")):
        fail(f"no osd_eval.py in {tools} (the shared tools folder beside the data folder)")
    sys.path.insert(0, tools)
    import osd_eval  # noqa: E402
    return osd_eval


def run_perceive(cli, pcd, out_dir, config):
    """Runs perceive; returns (wall seconds, result dict or None, error text)."""
    cmd = [cli, "perceive", pcd, "--out", out_dir, "--no-report", "-q"]
    if config:
        cmd += ["--config", config]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        return wall, None, p.stderr.strip().splitlines()[-1:] or ["exit %d" % p.returncode]
    with open(os.path.join(out_dir, "result.json")) as f:
        return wall, json.load(f), None


def aggregate(osd_eval, gt_of, pred_dir, scenes, scored_as=None):
    """mOSD metrics over `scenes` (names), from per-scene counts as osd_eval sums them;
    `scored_as` names a scene for the scorer (which reads mOSD-style names, e.g. learn12)."""
    tot = {}
    for k, s in enumerate(scenes):
        pred = os.path.join(pred_dir, s, "labels.pcd")
        if not os.path.exists(pred):
            continue
        r = osd_eval.evaluate_scene(gt_of(s), pred, scored_as(k) if scored_as else s)
        for k, v in r.items():
            tot[k] = tot.get(k, 0) + v
    P = tot.get("tp", 0) / max(tot.get("pred_pts", 0), 1)
    R = tot.get("tp", 0) / max(tot.get("gt_pts", 0), 1)
    return {"scenes": len(scenes), "overlap_F": 2 * P * R / max(P + R, 1e-12),
            "pct_F75": tot.get("f75", 0) / max(tot.get("gt_objects", 0), 1),
            "F_os": tot.get("os_pts", 0) / max(tot.get("gt_pts", 0), 1),
            "F_us": tot.get("us_pts", 0) / max(tot.get("gt_pts", 0), 1),
            "gt_objects": tot.get("gt_objects", 0), "pred_objects": tot.get("pred_objects", 0),
            "category_acc": tot["cat_ok"] / tot["cat_total"] if tot.get("cat_total") else None,
            "category_objects": tot.get("cat_total", 0)}


def timing(per_scene):
    walls = {s: r["wall_s"] for s, r in per_scene.items() if r.get("wall_s") is not None}
    if not walls:
        return {}
    med = statistics.median(walls.values())
    worst = max(walls, key=walls.get)
    return {"median_s": med, "worst_s": walls[worst], "worst_scene": worst,
            "worst_over_median": walls[worst] / med if med > 0 else 0.0}


def perceive_split(args, name, scenes, pcd_of):
    out = os.path.join(args.out, name, "multicue")
    per_scene, failed = {}, []
    for k, s in enumerate(scenes):
        d = os.path.join(out, s)
        os.makedirs(d, exist_ok=True)
        wall, res, err = run_perceive(args.cli, pcd_of(s), d, args.config)
        print(f"\r{name}: {k + 1}/{len(scenes)} {s}            ", end="", file=sys.stderr,
              flush=True)
        if res is None:
            failed.append(s)
            per_scene[s] = {"wall_s": wall, "error": err}
            continue
        per_scene[s] = {"wall_s": wall, "objects": len(res["objects"]),
                        "support": res["support"] is not None,
                        "stages_ms": res.get("timings_ms", {})}
    print("", file=sys.stderr)
    return out, per_scene, failed


def run_peers(args, name, input_dir, scenes):
    if not args.peers:
        return None
    out = os.path.join(args.out, name, "lccp")
    p = subprocess.run([args.peers, "--method", "lccp", input_dir, out, "--scenes",
                        ",".join(scenes)], capture_output=True, text=True)
    if p.returncode != 0:
        print(f"{name}: mosd_peers failed: {p.stderr.strip()}", file=sys.stderr)
        return None
    times = {}
    for line in p.stdout.splitlines():
        m = re.match(r"\s*(\S+)\s+([0-9.]+)\s+\d+\s*$", line)  # scene, segment_ms, objects
        if m and m.group(1) in scenes:
            times[m.group(1)] = float(m.group(2)) / 1000.0
    return out, times


def mosd_split(args, osd_eval, name, folder):
    input_dir = os.path.join(args.data, "scans", folder)
    scenes = sorted((f[:-4] for f in os.listdir(input_dir) if f.endswith(".pcd")),
                    key=scene_number)
    pcd_of = lambda s: os.path.join(input_dir, s + ".pcd")  # noqa: E731
    out, per_scene, failed = perceive_split(args, name, scenes, pcd_of)
    peers = run_peers(args, name, input_dir, scenes)
    groups = {}
    for group, numbers in MOSD_GROUPS[name]:
        members = [s for s in scenes if scene_number(s) in numbers]
        if not members:
            continue
        g = {"multicue": aggregate(osd_eval, pcd_of, out, members)}
        if peers:
            g["lccp"] = aggregate(osd_eval, pcd_of, peers[0], members)
        groups[group] = g
    result = {"groups": groups, "all": {"multicue": aggregate(osd_eval, pcd_of, out, scenes)},
              "timing": timing(per_scene), "failed": failed,
              "no_objects": [s for s, r in per_scene.items() if r.get("objects") == 0],
              "per_scene": per_scene}
    if peers:
        result["all"]["lccp"] = aggregate(osd_eval, pcd_of, peers[0], scenes)
        if peers[1]:
            result["lccp_timing"] = timing({s: {"wall_s": t} for s, t in peers[1].items()})
    return result


def samples_split(args):
    folder = os.path.join(args.data, "scans")
    scenes = [s for s in SAMPLES if os.path.exists(os.path.join(folder, s + ".pcd"))]
    out, per_scene, failed = perceive_split(args, "samples", scenes,
                                            lambda s: os.path.join(folder, s + ".pcd"))
    for s in scenes:
        if s in failed:
            continue
        with open(os.path.join(out, s, "result.json")) as f:
            res = json.load(f)
        per_scene[s]["found"] = [
            {"category": o["category"], "points": o["points"],
             "model": o["model"].get("type"),
             "size_cm": [round(100 * v, 1)
                         for v in (o.get("grasp") or {}).get("dimensions", {}).values()]}
            for o in res["objects"]]
    return {"timing": timing(per_scene), "failed": failed, "per_scene": per_scene}


def sim_split(args, osd_eval, mode):
    import numpy as np
    from pcdio import read_pcd, write_pcd
    name = f"sim-{mode}"
    sim_dir = os.path.join(args.out, name, "scenes")
    cmd = [args.cli, "simulate", "scenes", "--out", sim_dir, "--scenes", str(args.sim_scenes),
           "--mode", mode, "--seed", str(args.sim_seed), "-q"]
    if args.sim_objects:
        cmd += ["--objects", args.sim_objects]
    meshes = os.path.join(args.data, "meshes", "tabletop")
    if args.mesh_split != "procedural":
        cmd += ["--meshes", meshes, "--mesh-split", args.mesh_split]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return {"error": p.stderr.strip()}
    frames = sorted(f[:-4] for f in os.listdir(sim_dir) if f.endswith(".pcd"))
    # Ground truth in the mOSD label convention the scorer reads: objects >= 20.
    gt_dir = os.path.join(args.out, name, "gt")
    os.makedirs(gt_dir, exist_ok=True)
    for f in frames:
        fields, w, h = read_pcd(os.path.join(sim_dir, f + ".pcd"))
        lab = fields["label"].astype(np.int64)
        finite = np.isfinite(fields["x"])
        gt = np.where(lab >= 10, lab + 10, np.where(finite, 1, 0)).astype(np.uint32)
        write_pcd(os.path.join(gt_dir, f + ".pcd"),
                  [("x", fields["x"]), ("y", fields["y"]), ("z", fields["z"]), ("label", gt)],
                  w, h)
    out, per_scene, failed = perceive_split(args, name, frames,
                                            lambda s: os.path.join(sim_dir, s + ".pcd"))
    gt_of = lambda s: os.path.join(gt_dir, s + ".pcd")  # noqa: E731
    scored_as = lambda k: f"sim{k}"  # noqa: E731
    res = {"all": {"multicue": aggregate(osd_eval, gt_of, out, frames, scored_as)},
           "timing": timing(per_scene), "failed": failed,
           "no_objects": [s for s, r in per_scene.items() if r.get("objects") == 0],
           "per_scene": per_scene}
    peers = run_peers(args, name, sim_dir, frames)
    if peers:
        res["all"]["lccp"] = aggregate(osd_eval, gt_of, peers[0], frames, scored_as)
        if peers[1]:
            res["lccp_timing"] = timing({s: {"wall_s": t} for s, t in peers[1].items()})
    return res


def fmt_group(g, categories=True):
    text = f"{g['overlap_F']:.3f} / {g['pct_F75']:.3f} / {g['F_os']:.3f}"
    if categories and g.get("category_acc") is not None:
        text += f" (categories {g['category_acc']:.3f} of {g['category_objects']})"
    return text


def print_tables(report):
    print("| split | scene type | multicue F / share F>=0.75 / F_os | LCCP F / share / F_os |")
    print("|---|---|---|---|")
    for split, r in report.items():
        if "groups" in r:
            for group, g in r["groups"].items():
                lccp = fmt_group(g["lccp"], False) if "lccp" in g else "-"
                print(f"| {split} | {group} | {fmt_group(g['multicue'])} | {lccp} |")
        if "all" in r:
            lccp = fmt_group(r["all"]["lccp"], False) if "lccp" in r["all"] else "-"
            print(f"| {split} | all | {fmt_group(r['all']['multicue'])} | {lccp} |")
    print()
    print("| split | median frame [s] | worst frame [s] | worst / median | worst scene | "
          "frames without objects | failed |")
    print("|---|---|---|---|---|---|---|")
    for split, r in report.items():
        t = r.get("timing") or {}
        if not t:
            continue
        print(f"| {split} | {t['median_s']:.3f} | {t['worst_s']:.3f} | "
              f"{t['worst_over_median']:.2f} | {t['worst_scene']} | "
              f"{', '.join(r.get('no_objects', [])) or '-'} | "
              f"{', '.join(r.get('failed', [])) or '-'} |")
        t = r.get("lccp_timing") or {}
        if t:
            print(f"| {split}, LCCP segmentation alone | {t['median_s']:.3f} | "
                  f"{t['worst_s']:.3f} | {t['worst_over_median']:.2f} | {t['worst_scene']} | - | - |")
    if "samples" in report:
        print()
        for s, r in report["samples"]["per_scene"].items():
            found = "; ".join(f"{o['category']} ({o['model']}, {o['points']} pts, "
                              f"{' x '.join(str(v) for v in o['size_cm'])} cm)"
                              for o in r.get("found", []))
            print(f"- {s}: {found or r.get('error')}")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.path.join(here, "..", "build"))
    ap.add_argument("--data", default=os.path.join(here, "..", "..", "shared", "data"))
    ap.add_argument("--out", default="/tmp/multicue-protocol")
    ap.add_argument("--splits", default="tune,validate,samples")
    ap.add_argument("--peers", default=None, help="mosd_peers binary for LCCP on the same frames")
    ap.add_argument("--config", default=None, help="perceive parameter file")
    ap.add_argument("--sim-modes", default="complex,mixed,stacked")
    ap.add_argument("--sim-scenes", type=int, default=10)
    ap.add_argument("--sim-seed", type=int, default=1000)
    ap.add_argument("--sim-objects", default=None,
                    help="objects per simulated scene MIN,MAX (default: each mode's range)")
    ap.add_argument("--mesh-split", default="test", choices=["tune", "test", "all", "procedural"])
    ap.add_argument("--json", default=None, help="also write the whole report here")
    args = ap.parse_args()
    args.cli = os.path.join(args.build, "multicue")
    if not os.access(args.cli, os.X_OK):
        fail(f"no multicue binary at {args.cli} (build first or give --build)")
    if not os.path.isdir(os.path.join(args.data, "scans")):
        fail(f"no scans/ folder in the data folder {args.data}")
    if args.peers and not os.access(args.peers, os.X_OK):
        fail(f"--peers {args.peers} is not an executable")
    if args.config and not os.path.exists(args.config):
        fail(f"--config {args.config} does not exist")
    splits = args.splits.split(",")
    for s in splits:
        if s not in ("tune", "validate", "samples", "sim"):
            fail(f"unknown split '{s}' (tune, validate, samples, sim)")
    osd_eval = load_scorer(args.data)
    report = {}
    for s in splits:
        if s == "tune":
            report["tune"] = mosd_split(args, osd_eval, "tune", "mosd-learn")
        elif s == "validate":
            report["validate"] = mosd_split(args, osd_eval, "validate", "mosd-validate")
        elif s == "samples":
            report["samples"] = samples_split(args)
        else:
            for mode in args.sim_modes.split(","):
                report[f"sim-{mode}"] = sim_split(args, osd_eval, mode)
    print_tables(report)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=1, default=float)
    return 1 if any(r.get("failed") or r.get("error") for r in report.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
