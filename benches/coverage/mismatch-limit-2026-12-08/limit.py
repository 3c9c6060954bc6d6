#!/usr/bin/env python3
"""Scores a fit's `mismatch_detection` against each draw's true spread.

Usage: limit.py RESULTS.jsonl [...]  (the coverage runner's full results, method fit)

Per fit that states a mismatch detection: the draw, its generator, the true `ct_sigma`, the
limit `at_most` (the upper end of event timing's 95 % interval of an unresolved spread), the
counts' evidence beside the final model and the spread the fit blocks chose; then how often
the limit held, over every draw and over those with a true spread above 0.
"""
import json
import sys


def rows(paths):
    for path in paths:
        for line in open(path):
            r = json.loads(line)
            if r.get("method") != "fit":
                continue
            out = r["outcome"].get("output")
            if not isinstance(out, dict):
                continue
            d = out.get("mismatch_detection")
            if d is None:
                continue
            truth = r["truth"]["values"].get("ct_sigma", 0.0)
            yield r["case"]["id"], r["case"]["generator"], truth, d, out["not_detected"].get("ct_sigma")


def main(paths):
    held = total = held_spread = total_spread = no_limit = called = 0
    for case, gen, truth, d, said in rows(paths):
        limit = d.get("at_most")
        z = d.get("recording_evidence")
        mark = "-"
        if limit is None:
            no_limit += 1
        else:
            ok = truth <= limit
            mark = "held" if ok else "MISSED"
            total += 1
            held += ok
            if truth > 0:
                total_spread += 1
                held_spread += ok
        called += bool(d.get("counts_call_for_it"))
        zs = "-" if z is None else f"{z:.1f}"
        lim = "-" if limit is None else f"{limit:.4f}"
        tried = d.get("tried_spread")
        ts = "-" if tried is None else f"{tried:.4f}"
        print(f"{case:12s} {gen:9s} truth {truth:.4f} at_most {lim:8s} {mark:6s} counts z {zs:7s} calls {int(bool(d.get('counts_call_for_it')))} tried {ts}  in not_detected: {said is not None}")
    print(f"limits held {held} of {total}; with a true spread > 0: {held_spread} of {total_spread}; no limit (no interval) {no_limit}; counts call for a spread {called}")


if __name__ == "__main__":
    main(sys.argv[1:])
