#!/usr/bin/env python3
"""The README stays a front page: at most 300 lines, no commit hash outside its figures table
(dated runs and comparisons between commits belong in docs/measurements-log.md), and every
relative link points at a file of the repository.

Usage: readme_check.py README.md   (exit 1 with one line per problem)
"""
import os
import re
import sys

MAX_LINES = 300
FIGURES_HEADING = "## Current figures"
# A word of 7-40 hex digits with a digit and a letter in it: what git prints for a commit.
COMMIT = re.compile(r"\b(?=[0-9a-f]*[0-9])(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b")
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


def problems(path):
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    found = []
    if len(lines) > MAX_LINES:
        found.append(f"{path}: {len(lines)} lines, more than {MAX_LINES}: move dated runs to docs/measurements-log.md")
    in_figures_table = False
    in_code = False
    for number, line in enumerate(lines, 1):
        if line.startswith("```"):
            in_code = not in_code
        if line.startswith("## "):
            in_figures_table = line.strip() == FIGURES_HEADING
        is_table_row = line.lstrip().startswith("|")
        if not (in_figures_table and is_table_row) and not in_code:
            for match in COMMIT.finditer(line):
                found.append(f"{path}:{number}: commit hash {match.group(0)} outside the figures table")
        for target in LINK.findall(line):
            if "://" in target or target.startswith("mailto:"):
                continue
            if not os.path.exists(os.path.join(os.path.dirname(os.path.abspath(path)), target)):
                found.append(f"{path}:{number}: link to {target}, which does not exist")
    return found


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    found = problems(sys.argv[1])
    for p in found:
        print(p)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
