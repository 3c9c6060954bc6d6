"""ct_sigma of `estimate aps`: the absolute method systematic (ln units) whose addition in
quadrature covers 95 % of the measured draws, checked on held-out draws."""
import json, math, os, statistics

# the study folders this script reads, beside its own
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..') + '/'
def load(f):
    out = []
    for l in open(f):
        r = json.loads(l)
        if r['method'] != 'aps': continue
        s = r.get('reported', {}).get('ct_sigma')
        if not s or s.get('status') != 'interval': continue
        out.append((r['case']['seed'], r['case']['params'].get('ct_sigma', 0.0), s['value'], s['lo'], s['hi']))
    return out
def widened(row, a):
    seed, t, v, lo, hi = row
    add = 1.96 * a
    return max(0.0, v - math.hypot(v - lo, add)), v + math.hypot(hi - v, add)
def coverage(rows, a):
    return sum(lo <= r[1] <= hi for r in rows for lo, hi in [widened(r, a)]) / len(rows)
def half(rows, a):
    return statistics.median((widened(r, a)[1] - widened(r, a)[0]) / 2 for r in rows)
measured = load(ROOT + 'first100-2026-11-29/results.compact.jsonl') + load(ROOT + 'aps-systematic-2026-11-29/measured-1001-1080/results.compact.jsonl')
held = load(ROOT + 'aps-systematic-2026-11-29/heldout-2001-2080/results.compact.jsonl')
print(f'measured {len(measured)} draws, held out {len(held)}')
print('| term | measured covered | held-out covered | median half-width (measured) |')
for a in [0, 0.005, 0.008, 0.010, 0.011, 0.012, 0.013, 0.014, 0.015, 0.02]:
    print(f'| {a:.3f} | {coverage(measured, a):.1%} | {coverage(held, a):.1%} | {half(measured, a):.4f} |')

def flips(rows, a):
    """Draws whose widened interval reaches 0: reported `null` with an upper bound."""
    out = [(r[0], r[1], widened(r, a)[1]) for r in rows if r[2] - math.hypot(r[2] - r[3], 1.96 * a) <= 0]
    return out
for a in [0.012, 0.013]:
    for name, rows in [('measured', measured), ('held', held)]:
        f = flips(rows, a)
        print(a, name, 'not resolved', len(f), 'upper bound holds', sum(t <= u for _, t, u in f))

def resolved_coverage(rows, a):
    """As the study's table counts: a spread whose interval reaches 0 is `null` (not determinable)."""
    kept = [r for r in rows if r[2] - math.hypot(r[2] - r[3], 1.96 * a) > 0]
    return sum(lo <= r[1] <= hi for r in kept for lo, hi in [widened(r, a)]), len(kept)
for a in [0.0, 0.012]:
    for name, rows in [('measured', measured), ('held', held)]:
        print(a, name, 'resolved and covered / resolved', resolved_coverage(rows, a))
