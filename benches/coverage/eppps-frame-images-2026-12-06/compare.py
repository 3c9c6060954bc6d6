"""Prints table.md from results.jsonl: eppps (and the fit, where it was run) before and
after frames whose flow is not followed stood in for the natural-image prior."""
import json
from collections import Counter

rows = [json.loads(line) for line in open("results.jsonl")]


def cell(r, key):
    v, ci = r[key], r[key + "_ci95"]
    if v is None:
        return "n/d", "n/d"
    lo = 0.0 if ci[0] is None else ci[0]
    hi = float("inf") if ci[1] is None else ci[1]
    hit = lo <= r["truth"][key] <= hi
    return f"{v:.3f} [{lo:.3f}, {hi:.2f}]" + ("" if hit else " **miss**"), "in" if hit else "miss"


tally = Counter()
print("| draw | generator, DN, px/s, frames Hz | method | truth ON / OFF | before ON | before OFF | after ON | after OFF |")
print("|---|---|---|---|---|---|---|---|")
seen = {}
for r in rows:
    seen.setdefault((r["case_id"], r["method"]), {})[r["binary"]] = r
for (case, method), sides in seen.items():
    b = sides["before"]
    cells = []
    for side in ("before", "after"):
        for key in ("ct_on", "ct_off"):
            text, outcome = cell(sides[side], key)
            tally[(method, side, outcome)] += 1
            cells.append(text)
    what = f"{b['generator']}, {b['mean_dn']:.0f}, {b['speed_px_s']:.0f}, {b['aps_rate_hz']:.0f}"
    t = b["truth"]
    print(f"| {case} | {what} | {method} | {t['ct_on']:.3f} / {t['ct_off']:.3f} | " + " | ".join(cells) + " |")
print()
print("| method | binary | covered | missed |")
print("|---|---|---|---|")
for method in ("eppps", "fit"):
    for side in ("before", "after"):
        print(f"| {method} | {side} | {tally[(method, side, 'in')]} | {tally[(method, side, 'miss')]} |")
