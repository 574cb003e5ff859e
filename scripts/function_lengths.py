#!/usr/bin/env python3
"""Lists the longest function bodies of the C++ sources (lines from the signature to the closing
brace), to keep functions short.

    scripts/function_lengths.py [--top N] [--min LINES] [PATH ...]   (default: src apps eval bench)

A function is a top-level or namespace-level definition: a line ending in '{' whose text since
the previous statement contains a parameter list, outside class bodies and lambdas' enclosing
statements. Good enough for this code base's formatting (clang-format, Google style); it is not
a C++ parser.
"""

import argparse
import pathlib
import re
import sys

SKIP = re.compile(r"^\s*(namespace|struct|class|enum|union|extern|template\s*<[^>]*>\s*(struct|class))\b")
CONTROL = re.compile(r"^\s*(if|for|while|switch|do|else|try|catch|return)\b")


def strip(line):
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])*'", "''", line)
    return line.split("//")[0]


def functions(path):
    lines = path.read_text(errors="replace").splitlines()
    out = []
    depth = 0
    stack = []  # (kind, start line, name, depth before)
    pending = []  # text since the last statement at this depth
    in_comment = False
    for n, raw in enumerate(lines, 1):
        line = raw
        if in_comment:
            if "*/" not in line:
                continue
            line = line.split("*/", 1)[1]
            in_comment = False
        if "/*" in line and "*/" not in line.split("/*", 1)[1]:
            line = line.split("/*", 1)[0]
            in_comment = True
        code = strip(line)
        if code.strip().startswith("#"):
            continue
        for ch_i, ch in enumerate(code):
            if ch == "{":
                text = " ".join(pending) + " " + code[:ch_i]
                kind = "block"
                in_function = any(k == "function" for k, *_ in stack)
                if not in_function and not SKIP.match(text.strip()) and "(" in text \
                        and not CONTROL.match(text.strip()) and "=" not in text.split("(")[0]:
                    m = re.search(r"([A-Za-z_~][\w:~<>]*)\s*\(", text)
                    kind = "function"
                    name = m.group(1) if m else "?"
                    start = n - len([p for p in pending if p.strip()])
                    stack.append((kind, start, name, depth))
                else:
                    stack.append((kind, n, "", depth))
                depth += 1
                pending = []
            elif ch == "}":
                depth -= 1
                if stack:
                    kind, start, name, _ = stack.pop()
                    if kind == "function":
                        out.append((n - start + 1, name, str(path), start))
                pending = []
            elif ch == ";":
                pending = []
        rest = code.rsplit("{", 1)[-1].rsplit("}", 1)[-1].rsplit(";", 1)[-1]
        if rest.strip():
            pending.append(rest)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", default=["src", "apps", "eval", "bench"])
    ap.add_argument("--top", type=int, default=10)
    ap.add_argument("--min", type=int, default=0, help="list every function at least this long")
    args = ap.parse_args()
    found = []
    for p in args.paths:
        p = pathlib.Path(p)
        files = [p] if p.is_file() else sorted(p.rglob("*.cpp"))
        for f in files:
            found += functions(f)
    found.sort(key=lambda x: (-x[0], x[2], x[3]))
    rows = [f for f in found if f[0] >= args.min] if args.min else found[: args.top]
    for length, name, path, start in rows:
        print(f"{length:5d}  {name}  {path}:{start}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
