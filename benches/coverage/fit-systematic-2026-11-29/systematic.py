"""The fit's threshold intervals with a method systematic (a standard deviation of ln C)
added in quadrature to each side: coverage on the measured draws (seeds 1-100, committed
results of the fit of that day; seeds 1001-1080 run again on 2026-11-29) and on held-out
draws (seeds 2001-2080), from the committed compact results.

usage: python3 systematic.py
"""
import json, math, os, statistics

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, '..')


def load(path):
    rows = []
    for line in open(os.path.join(ROOT, path)):
        r = json.loads(line)
        if r['method'] != 'fit':
            continue
        for key in ('ct_on', 'ct_off'):
            s = r['reported'].get(key)
            if not s or s.get('status') != 'interval' or not s['lo'] or s['hi'] is None:
                continue
            rows.append((r['case']['params'][key], s['value'], s['lo'], s['hi']))
    return rows


def widened(row, term):
    truth, v, lo, hi = row
    add = 1.96 * term
    return v * math.exp(-math.hypot(math.log(v / lo), add)), v * math.exp(math.hypot(math.log(hi / v), add))


def coverage(rows, term):
    return sum(lo <= r[0] <= hi for r in rows for lo, hi in [widened(r, term)]) / len(rows)


def half_width(rows, term):
    return statistics.median(math.log(hi / lo) / 2 for r in rows for lo, hi in [widened(r, term)])


measured = load('first100-2026-11-29/results.compact.jsonl') + load('fit-systematic-2026-11-29/measured-1001-1080/results.compact.jsonl')
held = load('fit-ambiguity-2026-11-29/heldout-2001-2080/results.compact.jsonl')
print(f'measured: {len(measured)} polarity-cases, held out: {len(held)}\n')
print('| term (sd of ln C) | measured covered | held-out covered | median ln half-width, measured | held out |')
print('|---|---|---|---|---|')
for term in (0.0, 0.05, 0.10, 0.12, 0.13, 0.14, 0.15, 0.20, 0.25):
    print(f'| {term:.2f} | {coverage(measured, term):.1%} | {coverage(held, term):.1%} | {half_width(measured, term):.3f} | {half_width(held, term):.3f} |')
