#!/usr/bin/env python3
"""Compares two `et demo` summary.json files value by value and prints every value that
differs (times differ from run to run; every other number should not, unless a change meant
it to). A refactoring keeps all but the times.

Usage: python3 scripts/compare_summary.py OLD/summary.json NEW/summary.json
"""
import json
import sys


def walk(a, b, path, diffs, count):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                diffs.append((f"{path}/{k}", "only in one"))
            else:
                walk(a[k], b[k], f"{path}/{k}", diffs, count)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            diffs.append((path, f"{len(a)} against {len(b)} entries"))
            return
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", diffs, count)
    else:
        count[0] += 1
        if a != b:
            diffs.append((path, a, b))


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    old, new = (json.load(open(p)) for p in sys.argv[1:])
    diffs, count = [], [0]
    walk(old, new, "", diffs, count)
    print(f"{count[0]} values compared, {len(diffs)} differ")
    for d in diffs:
        print("  ", *d)


if __name__ == "__main__":
    main()
