#!/usr/bin/env python3
"""Checks the manual: README.md and every docs/**/*.md.

- Every relative link (inline `[text](target)`, images, reference definitions `[id]: target`)
  points to an existing file or folder of the repository.
- A link with `#anchor` to a Markdown file (or to a heading of the same page) names an existing
  heading of that file, with GitHub's slugs (lower case, punctuation dropped, spaces to hyphens,
  `-1`, `-2`, ... for repeated headings).
- No page mentions the data folder outside the repository (`../shared`, `shared/data`): users of
  the library do not have it.

Links inside code (fenced blocks, `code spans`) are not links and are skipped. Pages generated
from the code (GENERATED below) may be absent; links to them are then not checked.

usage: check_docs.py [REPO_ROOT]     (default: the folder above this script)
Prints one line per problem (file:line: message) and exits 1 if there is any, else 0.
"""

import os
import re
import sys
import unicodedata

# Pages generated from the code (the parameter reference); a link to one is fine while it is absent.
GENERATED = set()

FORBIDDEN = ["../shared", "shared/data"]

FENCE = re.compile(r"^\s*(```|~~~)")
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE_DEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
HTML_ANCHOR = re.compile(r"<a\s+(?:name|id)=\"([^\"]+)\"", re.IGNORECASE)
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
EXTERNAL = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def slug(heading_text):
    """GitHub's anchor of a heading: the rendered text, lower case, letters, digits, spaces,
    hyphens and underscores kept, every space a hyphen."""
    text = CODE_SPAN.sub(lambda m: m.group(2), heading_text)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML
    text = re.sub(r"(\*\*|__|\*)", "", text)  # emphasis markers
    text = text.strip().lower()
    kept = []
    for ch in text:
        cat = unicodedata.category(ch)
        if ch in " -_" or cat[0] in ("L", "N") or cat == "Mn":
            kept.append(ch)
    return "".join(kept).replace(" ", "-")


def strip_code_spans(line):
    return CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line)


def read_lines(path):
    with open(path, encoding="utf-8") as f:
        return f.read().split("\n")


def anchors_of(path, cache):
    """The anchors of a Markdown file: heading slugs (numbered when repeated) and HTML anchors."""
    if path in cache:
        return cache[path]
    anchors = set()
    counts = {}
    in_fence = False
    for line in read_lines(path):
        if FENCE.match(line):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        m = HEADING.match(line)
        if m:
            base = slug(m.group(2))
            n = counts.get(base, 0)
            anchors.add(base if n == 0 else f"{base}-{n}")
            counts[base] = n + 1
        for a in HTML_ANCHOR.findall(line):
            anchors.add(a)
    cache[path] = anchors
    return anchors


def links_of(lines):
    """(line number, target) of every link outside code."""
    in_fence = False
    for number, line in enumerate(lines, 1):
        if FENCE.match(line):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        text = strip_code_spans(line)
        for m in INLINE_LINK.finditer(text):
            yield number, m.group(1)
        m = REFERENCE_DEF.match(text)
        if m:
            yield number, m.group(1)


def pages(root):
    result = []
    readme = os.path.join(root, "README.md")
    if os.path.exists(readme):
        result.append(readme)
    for folder, dirs, files in os.walk(os.path.join(root, "docs")):
        dirs.sort()
        for name in sorted(files):
            if name.endswith(".md"):
                result.append(os.path.join(folder, name))
    return result


def check(root):
    problems = []
    cache = {}
    root = os.path.abspath(root)
    for page in pages(root):
        rel_page = os.path.relpath(page, root)
        lines = read_lines(page)
        for number, line in enumerate(lines, 1):
            for word in FORBIDDEN:
                if word in line:
                    problems.append(f"{rel_page}:{number}: mentions '{word}' (a folder outside the "
                                    "repository; name the dataset and use a variable such as $MOSD)")
        for number, target in links_of(lines):
            if EXTERNAL.match(target) or target.startswith("//"):
                continue
            path_part, _, anchor = target.partition("#")
            path_part = path_part.split("?", 1)[0]
            if path_part:
                if path_part.startswith("/"):
                    problems.append(f"{rel_page}:{number}: absolute link '{target}' (use a path "
                                    "relative to the page)")
                    continue
                resolved = os.path.normpath(os.path.join(os.path.dirname(page), path_part))
            else:
                resolved = page
            rel_target = os.path.relpath(resolved, root)
            if rel_target.startswith(".."):
                problems.append(f"{rel_page}:{number}: link '{target}' leaves the repository")
                continue
            if not os.path.exists(resolved):
                if rel_target.replace(os.sep, "/") in GENERATED:
                    continue
                problems.append(f"{rel_page}:{number}: link '{target}': no file {rel_target}")
                continue
            if anchor and resolved.endswith(".md") and os.path.isfile(resolved):
                if anchor not in anchors_of(resolved, cache):
                    problems.append(f"{rel_page}:{number}: link '{target}': no heading "
                                    f"'#{anchor}' in {rel_target}")
    return problems


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print(f"check_docs: {len(problems)} problem(s)")
        return 1
    print(f"check_docs: {len(pages(os.path.abspath(root)))} pages, links and anchors fine")
    return 0


if __name__ == "__main__":
    sys.exit(main())
