"""Side by side, per on-screen draw: `estimate screen`'s thresholds and 95 % intervals in two
coverage runs (results.compact.jsonl or results.jsonl), and the coverage, median relative
half-width and median seconds of each.

    python3 compare.py BEFORE.jsonl AFTER.jsonl
"""

import json
import statistics
import sys


def screen_runs(path):
    runs = {}
    for line in open(path):
        r = json.loads(line)
        if r.get("method") == "screen":
            runs[r["case"]["id"]] = r
    return runs


def cell(r, key, truth):
    x = r["reported"].get(key, {})
    if x.get("status") != "interval":
        return f"{x.get('status')}", None, None
    hit = x["lo"] <= truth <= x["hi"]
    half = (x["hi"] - x["lo"]) / 2 / x["value"]
    text = f"{x['value']:.3f} [{x['lo']:.3f}, {x['hi']:.3f}]" + ("" if hit else " **miss**")
    return text, hit, half


def main(before_path, after_path):
    runs = [screen_runs(before_path), screen_runs(after_path)]
    summary = [dict(hits=0, scored=0, halves=[], seconds=[]) for _ in runs]
    print("| draw | response | Cp | Cn | before Cp | before Cn | after Cp | after Cn |")
    print("|---|---|---|---|---|---|---|---|")
    for cid in sorted(runs[1]):
        a = runs[1][cid]
        truth = a["truth"]["values"]
        response = a["case"]["params"].get("log_response", "v2e")
        row = [cid[5:], response, f"{truth['ct_on']:.3f}", f"{truth['ct_off']:.3f}"]
        for run, s in zip(runs, summary):
            r = run.get(cid)
            if r is None:
                row += ["-", "-"]
                continue
            s["seconds"].append(r["seconds"])
            for key in ("ct_on", "ct_off"):
                text, hit, half = cell(r, key, truth[key])
                row.append(text)
                if hit is not None:
                    s["hits"] += hit
                    s["scored"] += 1
                    s["halves"].append(half)
        print("| " + " | ".join(row) + " |")
    print()
    for name, s in zip(("before", "after"), summary):
        if s["scored"]:
            print(
                f"{name}: {s['hits']}/{s['scored']} covered ({100 * s['hits'] / s['scored']:.1f} %), "
                f"median half-width {100 * statistics.median(s['halves']):.0f} %, "
                f"median {statistics.median(s['seconds']):.0f} s"
            )


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
