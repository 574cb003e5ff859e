#!/usr/bin/env python3
"""Single features, their concatenation and ensembles (thesis Tables 3.1 and 3.2, section 3.3).

From the dataset of common.py, four feature types (VFH, GRSD-, part statistics, HSV colour
histogram). Each run makes a three-way split by instance (section 3.3.5.1: level-0 training,
level-1 training, test; no instance in two parts), min-max scaling fitted on level 0. Error rates
on the test part of linear SVM and Real AdaBoost trained on level 0 with each single feature and
with the concatenation (also trained on level 0 + level 1, all the labelled data), and of every
ensemble rule over members trained on single features and pairs of features (stacking's level-1
classifier: linear SVM on the members' confidences). Mean over SPLITS shuffled splits.
Usage: eval/experiments/classification.py  (env: MULTICUE, WORK, MESHES, JOBS, SPLITS)
"""

import os
import statistics

import common

BLOCKS = [("vfh", "VFH"), ("grsd-minus", "GRSD-"), ("part-stats", "part stats"),
          ("colour", "colour")]
CLASSIFIERS = [("svm:kernel=linear", "SVM-linear"), ("boost:type=real,weak=100", "AdaBoost")]
SPLITS = int(os.environ.get("SPLITS", "5"))


def mean(v):
    return statistics.mean(v), (statistics.stdev(v) if len(v) > 1 else 0.0)


def main():
    data = common.dataset()
    four = common.path("b_four.mcd")
    common.run("dataset", "select", data, "--blocks", ",".join(b for b, _ in BLOCKS), "-o", four)
    single = {}
    ens = {}
    for s in range(1, SPLITS + 1):
        p = common.path(f"b_split{s}")
        common.run("dataset", "split", four, "--method", "three-way", "--shuffle", "--seed", s,
                   "-o", p)
        common.run("dataset", "normalise", p + "_level0.mcd", "--method", "minmax", "--save",
                   p + ".mcx", "-o", p + "_l0.mcd")
        for part in ("level1", "test"):
            common.run("dataset", "normalise", f"{p}_{part}.mcd", "--apply", p + ".mcx", "-o",
                       f"{p}_{part[:2] if part == 'test' else 'l1'}.mcd")
        l0, l1, test = p + "_l0.mcd", p + "_l1.mcd", p + "_te.mcd"
        common.run("dataset", "concat", l0, l1, "--rows", "-o", p + "_l01.mcd")
        for spec, cname in CLASSIFIERS:
            model = common.path("b_model.mcm")
            for b, _ in BLOCKS + [("all", "")]:
                args = [] if b == "all" else ["--blocks", b]
                common.run("classifier", "train", l0, "--spec", spec, *args, "-o", model)
                r = common.run_json("classifier", "eval", model, test, *args)
                single.setdefault((cname, b), []).append(r["error_rate"])
            common.run("classifier", "train", p + "_l01.mcd", "--spec", spec, "-o", model)
            r = common.run_json("classifier", "eval", model, test)
            single.setdefault((cname, "all01"), []).append(r["error_rate"])
            for subsets in ("singles", "singles+doubles"):
                e = common.path("b_ens.mce")
                common.run("ensemble", "train", l0, l1, "--member", spec, "--subsets", subsets,
                           "--level1", "svm:kernel=linear", "-o", e)
                r = common.run_json("ensemble", "eval", e, test)
                for rule in r["rules"]:
                    ens.setdefault((cname, subsets, rule["rule"]), []).append(rule["error_rate"])
    info = common.run("dataset", "info", p + "_te.mcd", capture=True).splitlines()[0]
    print(f"{SPLITS} three-way splits by instance; last test part: {info}\n")
    print("| classifier | " + " | ".join(n for _, n in BLOCKS) +
          " | all (level 0) | all (level 0 + 1) |")
    print("|---" * (len(BLOCKS) + 3) + "|")
    for _, cname in CLASSIFIERS:
        cells = []
        for b in [b for b, _ in BLOCKS] + ["all", "all01"]:
            m, sd = mean(single[(cname, b)])
            cells.append(f"{m:.3f} ± {sd:.3f}")
        print(f"| {cname} | " + " | ".join(cells) + " |")
    print("\nEnsembles (members trained on level 0, rule statistics / stacking on level 1); "
          "(w/n): splits in which the rule's error is below that of the same classifier on the "
          "concatenation trained on level 0\n")
    cols = [(c, sub) for _, c in CLASSIFIERS for sub in ("singles", "singles+doubles")]
    print("| rule | " + " | ".join(f"{c}, {sub}" for c, sub in cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    rules = []
    for key in ens:
        if key[2] not in rules:
            rules.append(key[2])
    for rule in rules:
        cells = []
        for c, sub in cols:
            v = ens[(c, sub, rule)]
            m, sd = mean(v)
            wins = sum(a < b for a, b in zip(v, single[(c, "all")]))
            cells.append(f"{m:.3f} ± {sd:.3f} ({wins}/{len(v)})")
        print(f"| {rule} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
