#!/usr/bin/env python3
"""The draws whose frames' log offset one polarity does not give (`estimate aps`'s
`frame_offset_dn.estimate.by_polarity` holding a null beside a fitted offset), with their
thresholds, intervals and truth.

Usage: offset.py RESULTS.jsonl [...]  (the coverage runner's full results, method aps)
"""
import json
import sys


def covered(out, truth, key):
    value, ci = out.get(key), out.get(key + "_ci95")
    if value is None or ci is None:
        return "n.d."
    lo = 0.0 if ci[0] is None else ci[0]
    hi = float("inf") if ci[1] is None else ci[1]
    return "covered" if lo <= truth[key] <= hi else "MISSED"


def fmt(ci):
    return "-" if ci is None else "[" + ", ".join("open" if v is None else f"{v:.3f}" for v in ci) + "]"


def main(paths):
    n = 0
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            out = r["outcome"].get("output")
            if r.get("method") != "aps" or not isinstance(out, dict):
                continue
            n += 1
            est = (out.get("frame_offset_dn") or {}).get("estimate") or {}
            if est.get("source") != "fitted" or None not in (est.get("by_polarity") or [0, 0]):
                continue
            t = r["truth"]["values"]
            print(f"{r['case']['id']:11s} {r['case']['generator']:9s} dn {r['truth']['mean_dn']:6.1f} b {est['offset_dn']:5.1f} by polarity {est['by_polarity']} "
                  f"ON {out.get('ct_on') or float('nan'):.3f} {fmt(out.get('ct_on_ci95'))} for {t['ct_on']:.3f} {covered(out, t, 'ct_on')}; "
                  f"OFF {out.get('ct_off') or float('nan'):.3f} {fmt(out.get('ct_off_ci95'))} for {t['ct_off']:.3f} {covered(out, t, 'ct_off')}")
    print(f"{n} aps runs with a result")


if __name__ == "__main__":
    main(sys.argv[1:])
