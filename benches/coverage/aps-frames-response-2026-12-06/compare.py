"""Prints table.md from results.jsonl: `estimate aps` before and after the re-simulation
read the frames through the response the event timing chose, on the 13 draws where the
timing chose a pure ln(DN + b)."""
import json
from collections import Counter

rows = [json.loads(line) for line in open("results.jsonl")]
by_case = {}
for r in rows:
    by_case.setdefault(r["case_id"], {})[r["binary"]] = r


def cell(r, key):
    v, ci = r[key], r[key + "_ci95"]
    if v is None:
        return "n/d", "n/d"
    hit = ci[0] <= r["truth"][key] <= ci[1]
    return f"{v:.3f} [{ci[0]:.3f}, {ci[1]:.3f}]" + ("" if hit else " **miss**"), "in" if hit else "miss"


tally = Counter()
print("| draw | generator | truth ON / OFF | before ON | before OFF | after ON | after OFF |")
print("|---|---|---|---|---|---|---|")
for case, sides in by_case.items():
    t = sides["before"]["truth"]
    cells = []
    for side in ("before", "after"):
        for key in ("ct_on", "ct_off"):
            text, outcome = cell(sides[side], key)
            tally[(side, outcome)] += 1
            cells.append(text)
    gen = sides["before"]["generator"]
    print(f"| {case} | {gen} | {t['ct_on']:.3f} / {t['ct_off']:.3f} | " + " | ".join(cells) + " |")
print()
print("| | covered | missed | not determinable |")
print("|---|---|---|---|")
for side in ("before", "after"):
    print(f"| {side} | {tally[(side, 'in')]} | {tally[(side, 'miss')]} | {tally[(side, 'n/d')]} |")
