#!/usr/bin/env python3
"""Kills multicue's long jobs at random moments and checks what they leave behind.

    scripts/kill_test.py --cli build/multicue [--kills 50] [--jobs train,extract,...] [--seed 1]
                         [--work DIR] [--json report.json] [--kitchen-models DIR]

For each job (train, extract, simulate, import, run, classifier, convert, furniture, detect,
fixtures, containers, joints) it prepares inputs, runs the job once to completion for the reference output and its
duration, then N times: puts the previous output (another complete output) in place, starts the
job, kills its process with SIGKILL at a uniformly random moment within the reference duration,
and checks

* every output file is either the previous complete file or the new complete one, byte for byte
  (simulate: every frame the manifest lists is complete and equal to the reference; dataset
  extract, which saves its partial output on purpose, holds a subset of the reference rows);
* SQLite databases pass PRAGMA integrity_check and hold either the old or the new objects
  (import is all or nothing; run learns frame by frame);
* resumable jobs (dataset extract --resume) finish from there with the reference output, and every
  job re-run after the kill finishes with the reference output;
* a killed process cannot remove its temporary files (".NAME.tmp-PID-N" of the atomic writes):
  they are counted, and the re-run must have removed them.

Then a full disk: the job runs under `ulimit -f` with a limit below its output size and must exit
non-zero with one line naming the file, leaving the previous output intact.
Exit status 1 when a check fails. The summary is printed and, with --json, written.
"""

import argparse
import filecmp
import json
import os
import random
import shutil
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path


class Failure(Exception):
    pass


def sh(cmd, cwd=None, check=True, limit_kb=None, capture=True):
    """Runs a command (a list); with limit_kb under ulimit -f (1 KiB blocks in bash)."""
    if limit_kb is not None:
        cmd = ["bash", "-c", f"ulimit -f {limit_kb}; exec \"$@\"", "bash", *map(str, cmd)]
    r = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=capture, text=True)
    if check and r.returncode != 0:
        raise Failure(f"{' '.join(map(str, cmd))} failed ({r.returncode}): {r.stderr.strip()}")
    return r


def temp_leftovers(folder):
    return sorted(str(p) for p in Path(folder).rglob(".*.tmp-*"))


def same(a, b):
    return Path(a).is_file() and Path(b).is_file() and filecmp.cmp(a, b, shallow=False)


class Job:
    """One kind of long job: inputs, the command, the previous output and the checks."""
    name = ""
    names_output_on_full_disk = True

    def __init__(self, cli, work):
        self.cli, self.work = cli, Path(work) / self.name
        self.work.mkdir(parents=True, exist_ok=True)

    def cmd(self, out):  # the job writing into folder `out`
        raise NotImplementedError

    def prepare(self):  # inputs and, in self.old, the previous outputs
        pass

    def place_old(self, out):  # the previous complete output into `out`
        out.mkdir(parents=True, exist_ok=True)

    def check(self, out, ref):  # after a kill; raises Failure
        raise NotImplementedError

    def check_final(self, out, ref):  # after the job ran to the end
        self.check_equal_files(out, ref)

    def finish_cmd(self, out):  # the command that completes after a kill
        return self.cmd(out)

    def outputs(self):  # output files compared byte for byte
        return []

    def check_equal_files(self, out, ref):
        for f in self.outputs():
            if not same(out / f, ref / f):
                raise Failure(f"{self.name}: {f} differs from the reference after a full run")

    def check_old_or_new(self, out, ref, old):
        for f in self.outputs():
            p = out / f
            if not p.exists():
                raise Failure(f"{self.name}: {f} is missing (the previous one was lost)")
            if not (same(p, ref / f) or same(p, old / f)):
                raise Failure(f"{self.name}: {f} is neither the previous nor the new file "
                              f"({p.stat().st_size} bytes)")
        return ["new" if same(out / f, ref / f) else "old" for f in self.outputs()]

    def disk_full_limit_kb(self, ref):
        return 1


class SeededFileJob(Job):
    """A job writing one file (`output`); the previous output is the same job with another seed."""
    output = ""

    def prepare(self):
        self.old = self.work / "old"
        self.old.mkdir(exist_ok=True)
        sh(self.cmd(self.old, seed=2))

    def place_old(self, out):
        super().place_old(out)
        shutil.copy(self.old / self.output, out / self.output)

    def outputs(self):
        return [self.output]

    def check(self, out, ref):
        return self.check_old_or_new(out, ref, self.old)


class Train(SeededFileJob):
    name = "train"
    output = "model.mcpg"

    def cmd(self, out, seed=1):
        return [self.cli, "--threads", "2", "train", "--out", out / self.output, "--objects", "2",
                "--views", "2", "--max-parts", "3", "--table-scenes", "1", "--table-views", "1",
                "--seed", seed]


class Classifier(Job):
    name = "classifier"
    # libsvm hands its model over through a temporary file of its own, which the limit hits first;
    # the error names that file.
    names_output_on_full_disk = False

    def prepare(self):
        sh([self.cli, "simulate", "objects", "--count", "12", "--views", "6", "--out",
            self.work / "sim", "-q"])
        sh([self.cli, "dataset", "extract", "--manifest", self.work / "sim" / "manifest.json",
            "-o", self.work / "data.mcd", "-q"])
        self.old = self.work / "old"
        self.old.mkdir(exist_ok=True)
        sh(self.cmd(self.old, spec="knn:k=1"))

    def cmd(self, out, spec="svm:kernel=rbf,grid=1"):
        return [self.cli, "--threads", "2", "classifier", "train", self.work / "data.mcd", "-o",
                out / "model.mcm", "--spec", spec]

    def place_old(self, out):
        super().place_old(out)
        shutil.copy(self.old / "model.mcm", out / "model.mcm")

    def outputs(self):
        return ["model.mcm"]

    def check(self, out, ref):
        return self.check_old_or_new(out, ref, self.old)


class Simulate(Job):
    name = "simulate"

    def cmd(self, out, seed=1):
        return [self.cli, "--threads", "2", "simulate", "scenes", "--scenes", "4", "--views", "2",
                "--objects", "2,3", "--seed", seed, "--out", out, "-q"]

    def prepare(self):
        self.old = self.work / "old"
        sh(self.cmd(self.old, seed=2))

    def place_old(self, out):
        shutil.copytree(self.old, out)

    def outputs(self):
        return ["manifest.json"]

    def check(self, out, ref):
        manifest = out / "manifest.json"
        if not manifest.is_file():
            raise Failure("simulate: manifest.json is missing")
        try:
            m = json.loads(manifest.read_text())
        except ValueError as e:
            raise Failure(f"simulate: manifest.json is not complete JSON ({e})")
        from_old = same(manifest, self.old / "manifest.json")
        base = self.old if from_old else ref
        for scene in m["scenes"]:
            for f in scene["frames"]:
                p = out / f["file"]
                if not p.is_file():
                    raise Failure(f"simulate: {f['file']} listed in the manifest is missing")
                # The old run's frames may have been replaced by the new run's files of the same
                # name already; a listed frame must be one of the two complete files.
                if not (same(p, ref / f["file"]) or same(p, self.old / f["file"])):
                    raise Failure(f"simulate: {f['file']} is not a complete frame")
        return ["old" if from_old else ("new" if m.get("complete") else "partial")]

    def check_final(self, out, ref):
        self.check_equal_files(out, ref)
        for p in ref.glob("*.pcd"):
            if not same(p, out / p.name):
                raise Failure(f"simulate: {p.name} differs from the reference after a re-run")


class Extract(Job):
    """dataset extract --resume: saves its partial output on purpose and continues from it."""
    name = "extract"

    def prepare(self):
        sh([self.cli, "simulate", "objects", "--count", "6", "--views", "4", "--out",
            self.work / "sim", "-q"])

    def cmd(self, out):
        return [self.cli, "--threads", "2", "dataset", "extract", "--manifest",
                self.work / "sim" / "manifest.json", "-o", out / "data.csv", "--resume",
                "--save-every", "2", "-q"]

    def outputs(self):
        return ["data.csv"]

    def rows(self, path):
        return path.read_text().splitlines()

    def check(self, out, ref):
        p = out / "data.csv"
        if not p.exists():
            return ["none"]
        rows, ref_rows = self.rows(p), self.rows(ref / "data.csv")
        if rows[0] != ref_rows[0] or rows[1:] != ref_rows[1:len(rows)]:
            raise Failure("extract: the partial output is not a prefix of the reference rows")
        return ["new" if rows == ref_rows else "partial"]


def integrity(db):
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        result = con.execute("PRAGMA integrity_check").fetchall()
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        # Killed between creating the file and its schema: an empty database, which the next
        # writer sets up (ObjectDatabase::Open).
        if "objects" not in tables:
            return 0, 0
        objects = con.execute("SELECT count(*) FROM objects").fetchone()[0]
        views = con.execute("SELECT count(*) FROM views").fetchone()[0]
    finally:
        con.close()
    if result != [("ok",)]:
        raise Failure(f"{db}: PRAGMA integrity_check says {result}")
    return objects, views


class Import(Job):
    name = "import"

    def prepare(self):
        # A large export: many objects with views, descriptors and meshes, so that the import
        # takes long enough to be killed half-way.
        mesh = "cGx5CmZvcm1hdCBhc2NpaSAxLjAKZW5kX2hlYWRlcgo=" * 40
        pose = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
        objects = [{"name": f"object-{i}", "category": "box", "created": i, "last_seen": i,
                    "last_pose": pose,
                    "views": [{"time": i + v, "frame": f"f{v}.pcd", "category": "box",
                               "category_probabilities": {"box": 0.8, "flat": 0.2},
                               "descriptors": {"vfh": [0.5] * 308, "grsd-": [1.0] * 21},
                               "model": {"type": "box", "extents": [0.1, 0.2, 0.3]},
                               "mesh_ply_base64": mesh, "pose": pose} for v in range(4)]}
                   for i in range(3000)]
        self.export = self.work / "export.json"
        self.export.write_text(json.dumps({"format": "multicue-object-database",
                                           "schema_version": 2, "objects": objects}))
        small = {"format": "multicue-object-database", "schema_version": 2,
                 "objects": objects[:3]}
        (self.work / "small.json").write_text(json.dumps(small))
        self.old = self.work / "old"
        self.old.mkdir(exist_ok=True)
        sh([self.cli, "db", "import", self.old / "objects.db", self.work / "small.json"])
        self.old_counts = integrity(self.old / "objects.db")

    def cmd(self, out):
        return [self.cli, "db", "import", out / "objects.db", self.export]

    def place_old(self, out):
        super().place_old(out)
        shutil.copy(self.old / "objects.db", out / "objects.db")

    def check(self, out, ref):
        counts = integrity(out / "objects.db")
        new = (self.old_counts[0] + 3000, self.old_counts[1] + 12000)
        if counts not in (self.old_counts, new):
            raise Failure(f"import: the database holds {counts} objects and views, neither the "
                          f"old {self.old_counts} nor the new {new} (not all or nothing)")
        return ["new" if counts == new else "old"]

    def finish_cmd(self, out):
        return None  # a second import would add the objects again

    def check_final(self, out, ref):
        integrity(out / "objects.db")


class Run(Job):
    """multicue run: learns objects into the database frame by frame, result JSON at the end."""
    name = "run"

    def prepare(self):
        sh([self.cli, "simulate", "scenes", "--scenes", "2", "--views", "2", "--objects", "2,2",
            "--out", self.work / "sim", "-q"])
        (self.work / "rules.json").write_text('{"category": {"categoriser": "rules"}}')
        self.old = self.work / "old"
        self.old.mkdir(exist_ok=True)
        (self.old / "run.json").write_text('{"previous": true}\n')

    def cmd(self, out):
        task = out / "task.yaml"
        task.write_text(f"task: enumerate\ndatabase: objects.db\nparams: {self.work}/rules.json\n"
                        f"output: run.json\nframes: {{manifest: {self.work}/sim/manifest.json}}\n")
        return [self.cli, "--threads", "2", "run", task]

    def place_old(self, out):
        super().place_old(out)
        shutil.copy(self.old / "run.json", out / "run.json")

    def outputs(self):
        return ["run.json"]

    def check(self, out, ref):
        state = self.check_old_or_new_json(out, ref)
        if (out / "objects.db").exists():
            integrity(out / "objects.db")
        return state

    def check_old_or_new_json(self, out, ref):
        p = out / "run.json"
        if same(p, self.old / "run.json"):
            return ["old"]
        try:
            json.loads(p.read_text())
        except ValueError as e:
            raise Failure(f"run: run.json is not complete JSON ({e})")
        return ["new"]

    def check_final(self, out, ref):
        # Killed before the database was created (the frames are read first): nothing to check.
        if (out / "objects.db").exists():
            integrity(out / "objects.db")

    def finish_cmd(self, out):
        return None  # a second run over the same frames learns other views: no fixed reference


class Convert(Job):
    """multicue convert of a large cloud: most of the time goes to writing, so kills land in the
    middle of the atomic write."""
    name = "convert"

    def prepare(self):
        import array
        n = 3_000_000
        rng = random.Random(3)
        xyz = array.array("f", (rng.uniform(-1.0, 1.0) for _ in range(3 * n)))
        header = (f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                  f"WIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary\n")
        with open(self.work / "big.pcd", "wb") as f:
            f.write(header.encode())
            xyz.tofile(f)
        self.old = self.work / "old"
        self.old.mkdir(exist_ok=True)
        sh([self.cli, "convert", self.work / "big.pcd", self.old / "out.pcd", "--format",
            "binary"])

    def cmd(self, out):
        return [self.cli, "convert", self.work / "big.pcd", out / "out.pcd", "--format", "ascii"]

    def place_old(self, out):
        super().place_old(out)
        shutil.copy(self.old / "out.pcd", out / "out.pcd")

    def outputs(self):
        return ["out.pcd"]

    def check(self, out, ref):
        return self.check_old_or_new(out, ref, self.old)


def train_furniture(cli, out, seed):
    """train furniture on procedural pieces only (no shared data needed)."""
    return [cli, "--threads", "2", "train", "furniture", "--out", out, "--meshes", "", "--kitchen",
            "", "--procedural", "3", "--views", "3", "--words", "10", "--verifier-rooms", "0",
            "--seed", seed, "-q"]


class Furniture(SeededFileJob):
    name = "furniture"
    output = "model.mcfm"

    def cmd(self, out, seed=1):
        return train_furniture(self.cli, out / self.output, seed)


class Fixtures(SeededFileJob):
    """train fixtures: simulated kitchens of the shared kitchen models (skipped without them)."""
    name = "fixtures"
    output = "fixtures.mcm"
    models = None  # the kitchen model library, from --kitchen-models

    def cmd(self, out, seed=1):
        return [self.cli, "--threads", "2", "train", "fixtures", "--out", out / self.output,
                "--kitchens", "1", "--views", "1", "--kitchen", self.models, "--seed", seed, "-q"]


class Containers(SeededFileJob):
    """train containers on kitchens of procedural units only (no shared data needed)."""
    name = "containers"
    output = "containers.mcm"

    def cmd(self, out, seed=1):
        return [self.cli, "--threads", "2", "train", "containers", "--out", out / self.output,
                "--kitchen", "none", "--procedural", "2", "--kitchens", "2", "--views", "1",
                "--laser-views", "0", "--seed", seed, "-q"]


class Joints(Containers):
    """train joints: the same kitchens and maps as containers, another model file."""
    name = "joints"
    output = "joints.mcm"

    def cmd(self, out, seed=1):
        c = super().cmd(out, seed)
        c[c.index("containers")] = "joints"
        return c


class Detect(Job):
    """detect furniture: three outputs (result.json, models.ply, report.html), each written
    atomically; the previous outputs come from a model trained with another seed."""
    name = "detect"

    def prepare(self):
        sh([self.cli, "--threads", "2", "simulate", "furniture", "--out", self.work / "scans",
            "--rooms", "1", "--heads", "2", "--split", "procedural", "--furniture", "",
            "--kitchen", "", "-q"])
        for seed in (1, 2):
            sh(train_furniture(self.cli, self.work / f"model{seed}.mcfm", seed))
        self.old = self.work / "old"
        self.old.mkdir(exist_ok=True)
        sh(self.cmd(self.old, seed=2))

    def cmd(self, out, seed=1):
        return [self.cli, "--threads", "2", "detect", "furniture",
                *sorted((self.work / "scans").glob("*.pcd")), "--model",
                self.work / f"model{seed}.mcfm", "--out", out, "-q"]

    def place_old(self, out):
        super().place_old(out)
        for f in self.outputs():
            shutil.copy(self.old / f, out / f)

    def outputs(self):
        return ["result.json", "models.ply", "report.html"]

    @staticmethod
    def same_result(a, b):  # result.json without its stage times
        def load(p):
            if not p.is_file():
                return None
            try:
                d = json.loads(p.read_text())
            except ValueError:
                return None
            d.pop("timing_ms", None)
            return d
        da = load(a)
        return da is not None and da == load(b)

    def check_equal_files(self, out, ref):
        if not self.same_result(out / "result.json", ref / "result.json"):
            raise Failure("detect: result.json differs from the reference after a full run")
        for f in self.outputs()[1:]:
            if not same(out / f, ref / f):
                raise Failure(f"detect: {f} differs from the reference after a full run")

    def check(self, out, ref):
        states = []
        for f in self.outputs():
            p = out / f
            if not p.exists():
                raise Failure(f"detect: {f} is missing (the previous one was lost)")
            if f == "result.json":
                new, old = self.same_result(p, ref / f), self.same_result(p, self.old / f)
            else:
                new, old = same(p, ref / f), same(p, self.old / f)
            if not (new or old):
                raise Failure(f"detect: {f} is neither the previous nor the new file "
                              f"({p.stat().st_size} bytes)")
            states.append("new" if new else "old")
        return states


JOBS = {j.name: j for j in [Train, Extract, Simulate, Import, Run, Classifier, Convert,
                            Furniture, Detect, Fixtures, Containers, Joints]}


def run_job(job, kills, rng, report):
    job.prepare()
    ref = job.work / "ref"
    shutil.rmtree(ref, ignore_errors=True)
    if job.name == "extract":
        ref.mkdir()
    else:
        job.place_old(ref)
    start = time.monotonic()
    sh(job.cmd(ref))
    duration = time.monotonic() - start
    states = {}
    leftovers = 0
    for k in range(kills):
        out = job.work / f"kill{k}"
        shutil.rmtree(out, ignore_errors=True)
        if job.name == "extract":
            out.mkdir()
        else:
            job.place_old(out)
        p = subprocess.Popen([str(c) for c in job.cmd(out)], stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, start_new_session=True)
        delay = rng.uniform(0.0, duration)
        try:
            p.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
        for s in job.check(out, ref):
            states[s] = states.get(s, 0) + 1
        leftovers += len(temp_leftovers(out))
        finish = job.finish_cmd(out)
        if finish is not None:
            # The run after the kill finishes the job and clears what the killed one left.
            sh(finish)
            job.check_final(out, ref)
            if temp_leftovers(out):
                raise Failure(f"{job.name}: temporary files left after the re-run: "
                              f"{temp_leftovers(out)}")
        else:
            job.check_final(out, ref)
        shutil.rmtree(out, ignore_errors=True)
    # Full disk: the previous output stays, the error names the file.
    out = job.work / "full"
    shutil.rmtree(out, ignore_errors=True)
    if job.name == "extract":
        out.mkdir()
        (out / "data.csv").write_text((ref / "data.csv").read_text().splitlines()[0] + "\n")
    else:
        job.place_old(out)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    r = sh(job.cmd(out), check=False, limit_kb=job.disk_full_limit_kb(ref))
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name in before}
    message = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ""
    full = {"exit": r.returncode, "message": message,
            "previous_intact": before == after, "leftovers": temp_leftovers(out)}
    if r.returncode == 0:
        raise Failure(f"{job.name}: exit 0 under ulimit -f {job.disk_full_limit_kb(ref)}")
    if not full["previous_intact"]:
        raise Failure(f"{job.name}: the previous output changed under a full disk")
    # One line naming the file; the atomic writes add the system's reason ("File too large"),
    # SQLite says it its own way ("disk I/O error", "database or disk is full").
    if job.names_output_on_full_disk and str(out) not in message:
        raise Failure(f"{job.name}: the full-disk error does not name the file: {message!r}")
    if job.name not in ("import", "run", "classifier") and "File too large" not in message:
        raise Failure(f"{job.name}: the full-disk error does not say why: {message!r}")
    if job.name == "import":
        integrity(out / "objects.db")
    shutil.rmtree(out, ignore_errors=True)
    report[job.name] = {"kills": kills, "reference_seconds": round(duration, 2),
                        "outcomes": states, "temp_files_left": leftovers, "full_disk": full}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", required=True)
    ap.add_argument("--kills", type=int, default=50)
    ap.add_argument("--jobs", default=",".join(JOBS))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--work")
    ap.add_argument("--json")
    ap.add_argument("--kitchen-models", help="kitchen model library of the fixtures job")
    args = ap.parse_args()
    Fixtures.models = Path(args.kitchen_models) if args.kitchen_models else None
    cli = Path(args.cli).resolve()
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="multicue-kill-"))
    rng = random.Random(args.seed)
    report, failed = {}, False
    for name in args.jobs.split(","):
        if name == "fixtures" and (Fixtures.models is None or not Fixtures.models.is_dir()):
            print(f"{name}: skipped (no kitchen models: --kitchen-models)", flush=True)
            continue
        try:
            run_job(JOBS[name](cli, work), args.kills, rng, report)
            print(f"{name}: {json.dumps(report[name])}", flush=True)
        except Failure as e:
            failed = True
            print(f"{name}: FAILED: {e}", flush=True)
            report[name] = {"failed": str(e)}
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1) + "\n")
    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
