#!/usr/bin/env python3
"""The method systematic of `estimate aps`, measured on coverage results.

Usage: systematic.py RESULTS.compact.jsonl [...] [--was 0.13]

Each aps threshold interval (value +- 1.96 sqrt(error^2 + (was * value)^2)) is taken
apart into its measured error and the relative method systematic it was run with
(`--was`, 0 before the term existed); the term is replaced by each candidate and the
coverage of all polarity-cases printed. The term aps uses is the smallest candidate at
which 95 % are covered.
"""
import json
import math
import sys

Z95 = 1.959964


def rows(paths, was):
    out = []
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            if r["method"] != "aps":
                continue
            for key in ("ct_on", "ct_off"):
                rep = r["reported"].get(key, {})
                if rep.get("status") != "interval" or rep["lo"] is None or rep["hi"] is None:
                    continue
                value = rep["value"]
                total = (rep["hi"] - rep["lo"]) / 2 / Z95
                measured = math.sqrt(max(total**2 - (was * value) ** 2, 0.0))
                out.append((value, measured, r["truth"]["values"][key]))
    return out


def main():
    args = sys.argv[1:]
    was = 0.0
    if "--was" in args:
        i = args.index("--was")
        was = float(args[i + 1])
        del args[i : i + 2]
    data = rows(args, was)
    errors = sorted(abs(math.log(v / t)) for v, _, t in data)
    print(f"{len(data)} polarity-cases; |ln error| median {errors[len(errors) // 2]:.3f}, "
          f"90th percentile {errors[int(0.9 * len(errors))]:.3f}")
    chosen = None
    for k in range(0, 41):
        term = k / 200
        covered = sum(abs(v - t) <= Z95 * math.hypot(m, term * v) for v, m, t in data)
        widths = sorted(Z95 * math.hypot(m, term * v) / v for v, m, _ in data)
        line = (f"term {term:.3f}: {covered}/{len(data)} = {100 * covered / len(data):.1f} %, "
                f"median relative half-width {100 * widths[len(widths) // 2]:.0f} %")
        if k % 4 == 0 or (chosen is None and covered >= 0.95 * len(data)):
            print(line)
        if chosen is None and covered >= 0.95 * len(data):
            chosen = term
    print(f"smallest term covering 95 %: {chosen}")


if __name__ == "__main__":
    main()
