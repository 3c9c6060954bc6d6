#!/usr/bin/env python3
"""The fit's hot_pixel_fraction before and after, draw by draw, from two sets of coverage
results (`results.jsonl` or `results.compact.jsonl` of `coverage --methods fit`).

    compare.py --before B1.jsonl [B2.jsonl ...] --after A1.jsonl [A2.jsonl ...]

Prints one line per draw run by both (truth, each interval) and the counts: draws without
hot pixels where the interval excludes 0 (a false claim), and draws with hot pixels where
the fraction is covered and where it is claimed (lower end above 0). A draw with hot pixels
is scored against the truth times min(1, 2 p(r)) from the fit's own detection curve, as the
study does (`src/coverage/summary/score.rs`)."""
import argparse
import json
import math


def load(paths):
    out = {}
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            if r.get("method") == "fit":
                out[r["case"]["id"]] = r
    return out


def detected_share(curve, rate):
    if not curve:
        return 1.0
    if rate <= curve[0][0]:
        return curve[0][1] if rate > 0 else 0.0
    for (r0, p0), (r1, p1) in zip(curve, curve[1:]):
        if rate <= r1:
            f = math.log(rate / r0) / math.log(r1 / r0)
            return p0 + f * (p1 - p0)
    return curve[-1][1]


def fraction(r):
    h = (r.get("reported") or {}).get("hot_pixel_fraction") or {}
    if h.get("status") != "interval":
        return None
    return h["value"], h.get("lo") or 0.0, h["hi"]


def curve_of(r):
    if "hot_detection" in r:
        return r["hot_detection"]
    out = (r.get("outcome") or {}).get("output") or {}
    d = out.get("hot_pixel_detection") or {}
    return d.get("probability")


def scored_truth(r):
    v = r["truth"]["values"]
    f = v.get("hot_pixel_fraction", 0.0)
    rate = v.get("hot_pixel_rate_hz")
    curve = curve_of(r)
    if f and rate and curve:
        f *= min(1.0, 2.0 * detected_share(curve, rate))
    return f


def show(x):
    return "-" if x is None else "%.2e [%.2e, %.2e]" % x


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--before", nargs="+", required=True)
    ap.add_argument("--after", nargs="+", required=True)
    a = ap.parse_args()
    before, after = load(a.before), load(a.after)
    tally = {k: [0, 0] for k in ("absent", "false claim", "present", "covered", "claimed")}
    for cid in sorted(set(before) & set(after), key=lambda c: int(c.split("-")[1])):
        true = after[cid]["truth"]["values"].get("hot_pixel_fraction", 0.0)
        row = [cid, "true %.2e" % true]
        for side, runs in enumerate((before, after)):
            f = fraction(runs[cid])
            row.append(show(f))
            if true == 0.0:
                tally["absent"][side] += 1
                tally["false claim"][side] += bool(f and f[1] > 0)
            else:
                t = scored_truth(runs[cid])
                tally["present"][side] += 1
                tally["covered"][side] += bool(f and f[1] <= t <= f[2])
                tally["claimed"][side] += bool(f and f[1] > 0)
        print(" | ".join(row))
    print()
    for k, (b, n) in tally.items():
        print("%-12s before %3d  after %3d" % (k, b, n))


if __name__ == "__main__":
    main()
