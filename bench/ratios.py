#!/usr/bin/env python3
"""Median times and peer/multicue ratios from bench_multicue's JSON output.

Usage:
    build/bench/bench_multicue --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
        --benchmark_out=res.json --benchmark_out_format=json
    python3 bench/ratios.py res.json [--markdown] [--memory] [--cpu]

Benchmark names are <operation>/<input>/<library>/threads:<n>. For every operation, input and
thread count it prints the median real time of each library in milliseconds and the ratio
peer/multicue (above 1: multicue is faster). The median comes from the `median` aggregate when the
run had repetitions, otherwise from the median of the plain runs. With --memory it also prints the
peak heap (MB) each call held and the size of its result (`out`: points read, voxels, normals
defined, finite inliers kept), which should agree between libraries that do the same work. With
--cpu it also prints single-thread CPU times (of the timing thread; multi-threaded CPU times would
miss the worker threads), which other load on the machine disturbs less than wall-clock times.
Python 3 standard library only.
"""

import argparse
import json
import statistics
import sys

LIBRARIES = ("multicue", "pcl", "open3d")
PEERS = ("pcl", "open3d")
OPERATIONS = ("load", "voxel_grid", "normals_radius", "normals_knn", "outlier_removal")
TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}


def parse_name(run_name):
    """Splits 'op/input/library/threads:N[/real_time]' into (op, input, library, threads)."""
    parts = run_name.split("/")
    if len(parts) < 4 or not parts[3].startswith("threads:"):
        return None
    return parts[0], parts[1], parts[2], int(parts[3].split(":", 1)[1])


def collect(paths):
    """Maps (op, input, library, threads) to {'ms', 'peak_heap_MB', 'out', 'error'}."""
    runs = {}
    medians = {}
    errors = {}
    for path in paths:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
        for b in data.get("benchmarks", []):
            key = parse_name(b.get("run_name", b.get("name", "")))
            if key is None:
                continue
            if b.get("error_occurred"):
                errors[key] = b.get("error_message", "skipped")
                continue
            unit = TO_MS[b.get("time_unit", "ns")]
            entry = {
                "ms": b["real_time"] * unit,
                "cpu_ms": b["cpu_time"] * unit,
                "peak_heap_MB": b.get("peak_heap_MB"),
                "out": b.get("out"),
            }
            if b.get("run_type") == "aggregate":
                if b.get("aggregate_name") == "median":
                    medians[key] = entry
            else:
                runs.setdefault(key, []).append(entry)
    result = {}
    for key, entries in runs.items():
        result[key] = {
            "ms": statistics.median(e["ms"] for e in entries),
            "cpu_ms": statistics.median(e["cpu_ms"] for e in entries),
            "peak_heap_MB": entries[-1]["peak_heap_MB"],
            "out": entries[-1]["out"],
        }
    result.update(medians)
    for key, message in errors.items():
        result.setdefault(key, {"error": message})
    return result


def order(values, preferred):
    known = [v for v in preferred if v in values]
    return known + sorted(v for v in values if v not in preferred)


def fmt_ms(entry, field="ms"):
    if entry is None:
        return "-"
    if "error" in entry:
        return "skipped"
    return f"{entry[field]:.2f}"


def fmt_ratio(peer, base, field="ms"):
    if not peer or not base or "error" in peer or "error" in base or base[field] <= 0:
        return "-"
    return f"{peer[field] / base[field]:.2f}"


def fmt_count(entry, field, digits=0):
    if entry is None or "error" in entry or entry.get(field) is None:
        return "-"
    return f"{entry[field]:.{digits}f}"


def print_table(header, rows, markdown):
    if markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "|".join("---" for _ in header) + "|")
        for row in rows:
            print("| " + " | ".join(row) + " |")
        return
    widths = [max(len(str(r[i])) for r in [header] + rows) for i in range(len(header))]
    for row in [header] + rows:
        print("  ".join(str(c).rjust(w) if i >= 3 else str(c).ljust(w)
                        for i, (c, w) in enumerate(zip(row, widths))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("json", nargs="+", help="Google Benchmark JSON output file(s)")
    parser.add_argument("--markdown", action="store_true", help="print Markdown tables")
    parser.add_argument("--memory", action="store_true",
                        help="also print peak heap [MB] and result sizes")
    parser.add_argument("--cpu", action="store_true",
                        help="also print single-thread CPU time medians and ratios (robust "
                             "against other load on the machine)")
    args = parser.parse_args()

    results = collect(args.json)
    if not results:
        sys.exit("no benchmarks named <operation>/<input>/<library>/threads:<n> found")
    ops = order({k[0] for k in results}, OPERATIONS)
    inputs = order({k[1] for k in results}, ())
    libraries = order({k[2] for k in results}, LIBRARIES)
    peers = [lib for lib in libraries if lib != "multicue"]
    threads = sorted({k[3] for k in results})

    header = ["operation", "input", "threads"] + [f"{lib} ms" for lib in libraries]
    header += [f"{peer}/multicue" for peer in peers]
    rows = []
    for op in ops:
        for inp in inputs:
            for n in threads:
                entries = {lib: results.get((op, inp, lib, n)) for lib in libraries}
                if not any(entries.values()):
                    continue
                row = [op, inp, str(n)] + [fmt_ms(entries[lib]) for lib in libraries]
                row += [fmt_ratio(entries[peer], entries.get("multicue")) for peer in peers]
                rows.append(row)
    print("Median real time [ms]; ratio = peer / multicue (above 1: multicue is faster)")
    print_table(header, rows, args.markdown)

    if args.cpu:
        header = ["operation", "input", "threads"] + [f"{lib} cpu ms" for lib in libraries]
        header += [f"{peer}/multicue" for peer in peers]
        rows = []
        for op in ops:
            for inp in inputs:
                entries = {lib: results.get((op, inp, lib, 1)) for lib in libraries}
                if not any(entries.values()):
                    continue
                row = [op, inp, "1"] + [fmt_ms(entries[lib], "cpu_ms") for lib in libraries]
                row += [fmt_ratio(entries[peer], entries.get("multicue"), "cpu_ms")
                        for peer in peers]
                rows.append(row)
        print()
        print("Single thread: median CPU time of the timing thread [ms]; ratio = peer / multicue")
        print_table(header, rows, args.markdown)

    if args.memory:
        header = ["operation", "input", "threads"]
        header += [f"{lib} heap MB" for lib in libraries] + [f"{lib} out" for lib in libraries]
        rows = []
        for op in ops:
            for inp in inputs:
                for n in threads:
                    entries = {lib: results.get((op, inp, lib, n)) for lib in libraries}
                    if not any(entries.values()):
                        continue
                    row = [op, inp, str(n)]
                    row += [fmt_count(entries[lib], "peak_heap_MB", 1) for lib in libraries]
                    row += [fmt_count(entries[lib], "out") for lib in libraries]
                    rows.append(row)
        print()
        print("Peak heap held by one call [MB] and result size (out)")
        print_table(header, rows, args.markdown)


if __name__ == "__main__":
    main()
