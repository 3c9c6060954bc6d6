"""Before/after table of `estimate eppps` with frames on the kept draws of five studies.

Run from this folder: python3 compare.py. Before: the binary of 7ecabf7 (HEAD before this
change); after: the still-pixel background. `before-s65-cases` had four runs that collided
with the after run in a shared case folder; `before-s65-rerun` holds them again.
"""
import json

SETS = [
    ("s65-cases", "seeds 7001-9030 (55 kept draws)"),
    ("s66-fresh10k-cases", "seeds 10001-10030"),
    ("s67-measured-cases", "seeds 2001-2080, 4001-4080"),
    ("s68-fresh11k-cases", "seeds 11001-11040, ctcal's simulator"),
    ("s68-peer11k-cases", "seeds 11001-11040, ctcal/ESIM/DVS-Voltmeter/IEBCS"),
]


def load(path):
    out = {}
    for line in open(path):
        d = json.loads(line)
        if d["method"] == "eppps":
            out[d["case"]["id"]] = d
    return out


def status(d, key):
    r = (d.get("reported") or {}).get(key)
    t = (d.get("truth") or {}).get("values", {}).get(key)
    if r is None:
        return "failed", None
    if r["status"] != "interval":
        return r["status"], None
    lo = r.get("lo") or 0.0
    hi = r["hi"] if r.get("hi") is not None else float("inf")
    return ("covered" if lo <= t <= hi else "missed"), (r["value"], lo, hi, t)


rows = []
changed = []
for name, what in SETS:
    before = load(f"before-{name}.results.compact.jsonl")
    if name == "s65-cases":
        before.update(load("before-s65-rerun.results.compact.jsonl"))
    after = load(f"after-{name}.results.compact.jsonl")
    cells = []
    for key in ("ct_on", "ct_off"):
        for tag, runs in (("before", before), ("after", after)):
            s = [status(runs[c], key)[0] for c in sorted(after)]
            cells.append(f"{s.count('covered')}/{s.count('covered') + s.count('missed')}")
        for c in sorted(after):
            b, a = status(before[c], key), status(after[c], key)
            if b != a:
                changed.append((c, name, key, b, a))
    rows.append(f"| {what} | {len(after)} | {cells[0]} -> {cells[1]} | {cells[2]} -> {cells[3]} |")
print("| draws | runs | Cp covered / determinable | Cn covered / determinable |")
print("|---|---|---|---|")
print("\n".join(rows))
print()
for c, name, key, b, a in changed:
    f = lambda s: s[0] if s[1] is None else f"{s[1][0]:.3f} [{s[1][1]:.3f}, {s[1][2]:.3f}] {s[0]}"
    print(f"{c} ({name}) {key}, truth {(b[1] or a[1] or [0, 0, 0, float('nan')])[3]:.3f}: {f(b)} -> {f(a)}")
