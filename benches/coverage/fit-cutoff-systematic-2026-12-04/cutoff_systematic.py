"""The fit's cutoff method systematic: the smallest term s (a standard deviation of
ln cutoff, added in quadrature to each side of the 95 % interval) that makes the fit's
cutoff intervals cover 95 % of the true cutoffs, from the committed coverage studies of the
fit since 2026-11-29 (the fit of earlier studies differs too much), and the held-out check
on any results given on the command line.

    python3 cutoff_systematic.py [HELD_OUT_RESULTS.jsonl ...]
"""
import glob
import json
import math
import os
import sys

Z95 = 1.959963984540054
HERE = os.path.dirname(os.path.abspath(__file__))
STUDIES = [
    "fit-1001-1080-2026-11-29", "fit-systematic-2026-11-29", "fit-ambiguity-2026-11-29",
    "hot-mismatch-tail-2026-11-29", "heldout-3001-3080-2026-11-29", "fresh-4001-4080-2026-12-01",
    "refractory-mismatch-2026-12-02", "noise-radius-2026-12-03", "fresh-6001-6040-fit-2026-12-02",
    "fresh-7001-7040-2026-12-04", "fresh-8001-8030-2026-12-04",
]


def intervals(paths):
    """(seed, truth, value, lo, hi) of every fit cutoff interval with a true cutoff, the
    latest study's where a draw appears twice."""
    out = {}
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            if r.get("method") != "fit":
                continue
            truth = r["case"]["params"].get("cutoff_hz")
            x = r.get("reported", {}).get("cutoff_hz", {})
            if truth and x.get("status") == "interval":
                out[r["case"]["seed"]] = (truth, x["value"], x["lo"], x["hi"])
    return out


def needed(truth, value, lo, hi):
    """The term s the interval needs to cover the truth (0: it does; inf: it cannot)."""
    if (lo is None or lo <= truth) and (hi is None or truth <= hi):
        return 0.0
    if value <= 0:
        return math.inf
    if lo is not None and truth < lo:
        d, h = math.log(value / truth), math.log(value / lo) if value > lo > 0 else 0.0
    else:
        d, h = math.log(truth / value), math.log(hi / value) if hi > value else 0.0
    return math.sqrt(max(d * d - h * h, 0.0)) / Z95 if d > 0 else math.inf


def coverage(rows, s):
    return sum(needed(*r) <= s + 1e-12 for r in rows.values()) / len(rows)


def main():
    paths = []
    for study in STUDIES:
        found = glob.glob(os.path.join(HERE, "..", study, "**", "results*.jsonl"), recursive=True)
        # a study's state after its change, not the one before
        paths += sorted(p for p in found if "/before" not in p)
    rows = intervals(paths)
    print(f"{len(rows)} cutoff intervals; covered as reported: {coverage(rows, 0.0):.3f}")
    for seed, r in sorted(rows.items()):
        n = needed(*r)
        if n > 0:
            print(f"  miss: draw {seed} truth {r[0]:.1f} value {r[1]:.1f} [{r[2]}, {r[3]}] needs {n:.2f}")
    for s in (0.1, 0.15, 0.2, 0.21, 0.25, 0.3):
        print(f"  s = {s:.2f}: {coverage(rows, s):.3f}")
    for held in sys.argv[1:]:
        out = intervals([held])
        if out:
            print(f"held out {held}: {len(out)} intervals, {coverage(out, 0.0):.3f} -> {coverage(out, 0.21):.3f}")


if __name__ == "__main__":
    main()
