"""ct_sigma of `ctcal fit`: the absolute method systematic (ln units) whose addition in
quadrature covers 95 % of the measured draws, checked on held-out draws.

Usage: python3 sigma_systematic.py [EXTRA_HELD_OUT_RESULTS.jsonl ...]
Reads the committed results of the study folders named below (a draw seen in several
folders counts once, from the last folder listed)."""
import json, math, os, statistics, sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..') + '/'
MEASURED = ['first100-2026-11-29', 'fit-systematic-2026-11-29/measured-1001-1080',
            'fit-ambiguity-2026-11-29/heldout-2001-2080']
HELD_OUT = ['heldout-3001-3080-2026-11-29', 'fresh-4001-4080-2026-12-01',
            'refractory-mismatch-2026-12-02/fresh-5001-5040-after', 'second-look-2026-12-02/after']


def load(paths):
    """(seed, true spread, value, lo, hi, effects) of every fit that reported a spread."""
    latest = {}
    for f in paths:
        for l in open(f):
            r = json.loads(l)
            if r['method'] == 'fit':
                latest[r['case']['seed']] = r
    out = []
    for seed, r in sorted(latest.items()):
        s = r.get('reported', {}).get('ct_sigma')
        if not s or s.get('status') != 'interval':
            continue
        hi = s['hi'] if s['hi'] is not None else math.inf
        effects = [e for e in r['truth']['effects'] if e != 'mismatch']
        out.append((seed, r['case']['params'].get('ct_sigma', 0.0) or 0.0, s['value'], s['lo'] or 0.0, hi, effects))
    return out


def widened(row, a):
    _, _, v, lo, hi, _ = row
    add = 1.96 * a
    return max(0.0, v - math.hypot(v - lo, add)), v + math.hypot(hi - v, add)


def covered(rows, a):
    return sum(lo <= r[1] <= hi for r in rows for lo, hi in [widened(r, a)])


def half(rows, a):
    return statistics.median((min(w[1], 1.0) - w[0]) / 2 for r in rows for w in [widened(r, a)])


def folder(names):
    return [ROOT + n + '/results.compact.jsonl' for n in names]


measured = load(folder(MEASURED))
held = load(folder(HELD_OUT))
extra = load(sys.argv[1:]) if len(sys.argv) > 1 else []
print(f'measured {len(measured)} spreads, held out {len(held)}, given {len(extra)}')
print('| term | measured covered | held-out covered | given covered | median half-width (measured) |')
print('|---|---|---|---|---|')
for a in [0, 0.004, 0.006, 0.008, 0.009, 0.010, 0.012, 0.015, 0.02]:
    cells = [f'{covered(rows, a)}/{len(rows)} = {covered(rows, a) / max(len(rows), 1):.1%}'
             for rows in (measured, held, extra)]
    print(f'| {a:.3f} | ' + ' | '.join(cells) + f' | {half(measured, a):.4f} |')
print()
for name, rows in [('measured', measured), ('held out', held), ('given', extra)]:
    for r in rows:
        lo, hi = widened(r, 0.0)
        if not lo <= r[1] <= hi:
            lo2, hi2 = widened(r, 0.010)
            print(f'{name}: seed {r[0]} truth {r[1]:.4f} value {r[2]:.4f} [{lo:.4f}, {hi:.4f}] -> '
                  f'[{lo2:.4f}, {hi2:.4f}] at 0.010 {"covered" if lo2 <= r[1] <= hi2 else "MISS"} '
                  f'({", ".join(r[5]) or "no other effect"})')
