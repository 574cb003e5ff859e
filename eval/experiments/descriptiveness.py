#!/usr/bin/env python3
"""Descriptiveness of the cluster features (thesis Tables 2.2 and 2.3, section 2.5.3).

k-NN category accuracy of each feature with the L1, L2, Hellinger, chi2 and Jeffries-Matusita
metrics on simulated Kinect scans of held-out instances: each run splits the objects by instance
(GroupSplit, 30 % of the instances of each category to test), so no mesh is in both parts; the
table gives mean +- standard deviation over SPLITS runs and the mean prediction time per query.
Usage: eval/experiments/descriptiveness.py  (env: MULTICUE, WORK, MESHES, JOBS, SPLITS, K)
"""

import os
import statistics

import common

FEATURES = [("vfh", "VFH [308d]"), ("grsd-minus", "GRSD- [21d]"), ("grsd", "GRSD [21d]"),
            ("pfh", "PFH mean [125d]"), ("fpfh", "FPFH mean [33d]"), ("rsd", "RSD mean [2d]"),
            ("part-stats", "part stats [24d]"), ("colour", "colour HSV [20d]")]
METRICS = [("l1", "L1"), ("l2", "L2"), ("hellinger", "Hellinger"), ("chi2", "χ²"),
           ("jm", "Jeffries–Matusita")]
SPLITS = int(os.environ.get("SPLITS", "5"))
K = os.environ.get("K", "1")


def main():
    data = common.dataset()
    acc = {}
    ms = {}
    for s in range(1, SPLITS + 1):
        prefix = common.path(f"a_split{s}")
        common.run("dataset", "split", data, "--method", "group", "--test-fraction", "0.3",
                   "--seed", s, "-o", prefix)
        for f, _ in FEATURES:
            for m, _ in METRICS:
                model = common.path("a_model.mcm")
                common.run("classifier", "train", prefix + "_train.mcd", "--spec",
                           f"knn:k={K},metric={m},threads=1", "--blocks", f, "-o", model)
                r = common.run_json("classifier", "eval", model, prefix + "_test.mcd", "--blocks", f)
                acc.setdefault((f, m), []).append(100.0 * r["accuracy"])
                ms.setdefault((f, m), []).append(r["predict_ms_per_row"])
    info = common.run("dataset", "info", prefix + "_test.mcd", capture=True).splitlines()[0]
    print(f"{SPLITS} splits by instance, k = {K}; last test part: {info}\n")
    header = "| k-NN metric | " + " | ".join(label for _, label in FEATURES) + " |"
    rule = "|---" * (len(FEATURES) + 1) + "|"
    print("Accuracy [%], mean ± std over the splits\n")
    print(header)
    print(rule)
    for m, mlabel in METRICS:
        cells = []
        for f, _ in FEATURES:
            v = acc[(f, m)]
            sd = statistics.stdev(v) if len(v) > 1 else 0.0
            cells.append(f"{statistics.mean(v):.1f} ± {sd:.1f}")
        print(f"| {mlabel} | " + " | ".join(cells) + " |")
    print("\nPrediction time per query [ms] (exact k-NN, one thread, mean over the splits)\n")
    print(header)
    print(rule)
    for m, mlabel in METRICS:
        print(f"| {mlabel} | " + " | ".join(f"{statistics.mean(ms[(f, m)]):.3f}"
                                             for f, _ in FEATURES) + " |")


if __name__ == "__main__":
    main()
