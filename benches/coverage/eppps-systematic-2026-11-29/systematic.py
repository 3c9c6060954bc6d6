#!/usr/bin/env python3
"""The method systematic of `estimate eppps` with frames, measured on coverage results.

Usage: systematic.py RESULTS.compact.jsonl [...] [--was 0.10]

Each eppps interval with frames is taken apart into its measured terms and the method
systematic it was run with (`--was`, in ln C); the term is then replaced by each candidate
and the coverage of all polarity-cases printed. The term eppps uses is the smallest
candidate at which 95 % are covered.
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
            if r["method"] != "eppps" or r["outcome"]["status"] != "ok":
                continue
            truth = r["truth"]
            if truth.get("aps_frames", 0) < 2:  # read without frames: another term
                continue
            for key in ("ct_on", "ct_off"):
                rep = r["reported"].get(key, {})
                if rep.get("status") != "interval" or rep["lo"] is None or rep["hi"] is None:
                    continue
                sd = (math.log(rep["hi"]) - math.log(rep["lo"])) / 2 / Z95
                measured = math.sqrt(max(sd * sd - was * was, 0.0))
                out.append((math.log(rep["value"] / truth["values"][key]), measured))
    return out


def main():
    args = sys.argv[1:]
    was = 0.10
    if "--was" in args:
        i = args.index("--was")
        was = float(args[i + 1])
        del args[i : i + 2]
    data = rows(args, was)
    errors = sorted(abs(e) for e, _ in data)
    print(f"{len(data)} polarity-cases with frames; |ln error| median "
          f"{errors[len(errors) // 2]:.3f}, 90th percentile {errors[int(0.9 * len(errors))]:.3f}")
    chosen = None
    for k in range(0, 61):
        term = k / 100
        covered = sum(abs(e) <= Z95 * math.hypot(m, term) for e, m in data)
        if k % 5 == 0 or (chosen is None and covered >= 0.95 * len(data)):
            print(f"term {term:.2f}: {covered}/{len(data)} = {100 * covered / len(data):.1f} %")
        if chosen is None and covered >= 0.95 * len(data):
            chosen = term
    print(f"smallest term covering 95 %: {chosen}")


if __name__ == "__main__":
    main()
