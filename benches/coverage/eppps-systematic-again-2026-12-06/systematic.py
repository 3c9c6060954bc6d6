#!/usr/bin/env python3
"""eppps with frames: its method systematic measured again, now that a slow photoreceptor's
low-passed reading is taken where the check fires.

Usage: systematic2.py --measure A.jsonl [...] --check B.jsonl [...]

Each eppps-with-frames interval is taken apart into each of its readings (the reported one;
where `photoreceptor_slow` adopted the low-passed scans, those and the ideal scans', whose
union the interval spans), each reading's measured terms found by taking out the method
systematic it was run with (0.37 in ln C, 0.46 for frames whose median is under 20 DN). The
term is then replaced by candidates, separately for bright and dim frames, and the coverage
printed; the chosen terms are the smallest covering 95 % of the measuring sets' cases.
"""
import json, math, sys

Z = 1.959964
WAS = {"bright": 0.37, "dim": 0.46}


def readings(out, key):
    pol = key.split("_")[1]
    slow = out.get("photoreceptor_slow")
    est = out["estimators"][0][key]
    if slow and slow.get("scanned", {}).get(pol, {}).get("value") is not None and slow.get("ideal", {}).get(pol):
        return [(slow["scanned"][pol]["value"], slow["scanned"][pol]["ci95"]),
                (slow["ideal"][pol]["value"], slow["ideal"][pol]["ci95"])]
    return [(est["value"], est["ci95"])]


def rows(paths):
    out_rows = []
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            if r["method"] != "eppps" or r["outcome"]["status"] != "ok":
                continue
            out = r["outcome"].get("output")
            if not out or r["truth"].get("aps_frames", 0) < 2:
                continue
            dn = out["estimators"][0]["details"].get("frames_median_dn")
            kind = "dim" if dn is not None and dn < 20 else "bright"
            for key in ("ct_on", "ct_off"):
                if out.get(key) is None:
                    continue
                truth = r["truth"]["values"][key]
                parts = []
                for value, (lo, hi) in readings(out, key):
                    if value is None or not lo or hi is None or lo <= 0:
                        parts.append(("open", lo or 0.0, hi if hi is not None else math.inf))
                        continue
                    sd = math.log(hi / lo) / 2 / Z
                    m = math.sqrt(max(sd * sd - WAS[kind] ** 2, 0.0))
                    parts.append(("ln", value, m))
                out_rows.append((r["case"]["id"], key, kind, truth, parts))
    return out_rows


def covered(row, term):
    _, _, _, truth, parts = row
    lo, hi = math.inf, 0.0
    for p in parts:
        if p[0] == "open":
            lo, hi = min(lo, p[1]), max(hi, p[2])
        else:
            w = Z * math.hypot(p[2], term)
            lo, hi = min(lo, p[1] * math.exp(-w)), max(hi, p[1] * math.exp(w))
    return lo <= truth <= hi


def table(data, kind, chosen=None):
    sel = [r for r in data if r[2] == kind]
    if not sel:
        return None
    first = None
    for k in range(0, 81):
        term = k / 100
        c = sum(covered(r, term) for r in sel)
        if first is None and c >= 0.95 * len(sel):
            first = term
        if k % 5 == 0 or term == first or (chosen is not None and abs(term - chosen) < 1e-9) or abs(term - WAS[kind]) < 1e-9:
            print(f"  {kind} term {term:.2f}: {c}/{len(sel)} = {100 * c / len(sel):.1f} %")
    return first


def main():
    args = sys.argv[1:]
    i = args.index("--check") if "--check" in args else len(args)
    measure, check = args[1:i], args[i + 1:]
    m = rows(measure)
    print(f"measuring: {len(m)} polarity-cases")
    chosen = {}
    for kind in ("bright", "dim"):
        chosen[kind] = table(m, kind)
        print(f"  smallest {kind} term covering 95 %: {chosen[kind]}")
    if check:
        c = rows(check)
        print(f"checking: {len(c)} polarity-cases")
        for kind in ("bright", "dim"):
            sel = [r for r in c if r[2] == kind]
            for term in sorted({WAS[kind], chosen[kind] or WAS[kind]}):
                n = sum(covered(r, term) for r in sel)
                print(f"  {kind} term {term:.2f}: {n}/{len(sel)} = {100 * n / max(len(sel), 1):.1f} %")


if __name__ == "__main__":
    main()
