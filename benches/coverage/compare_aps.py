"""Before/after comparison of `estimate aps --json` outputs on kept coverage draws: per draw
and polarity, covered / MISS / nd (not determinable) / err against the draw's truth,
printed where the coverage changed, the interval's width relative to the truth moved by
more than 2 % or (with --value-change) the value by more than that; with the reset hold the
AFTER run fitted where its JSON has one (`refractory_tracking`). Then the counts and the
median relative widths. The studies' own `compare.py` call it. Run from anywhere:

    python3 benches/coverage/compare_aps.py BEFORE AFTER CASES [CASES ...] [--value-change X]

BEFORE and AFTER hold `case-N.json`, each CASES folder `case-N/truth.json` (the first that
has the draw counts).
"""
import glob
import json
import os
import statistics
import sys

args = sys.argv[1:]
value_change = float('inf')
if '--value-change' in args:
    k = args.index('--value-change')
    value_change = float(args[k + 1])
    del args[k:k + 2]
A, B, case_dirs = args[0], args[1], args[2:]


def casedir(n):
    for base in case_dirs:
        if os.path.exists(base + '/' + n):
            return base + '/' + n


def load(p):
    try:
        return json.load(open(p))
    except Exception:
        return None


stats = {}
for p in sorted(glob.glob(B + '/case-*.json')):
    n = os.path.basename(p)[:-5]
    b = load(p)
    a = load(A + '/' + n + '.json')
    if b is None and a is None:
        continue
    t = json.load(open(casedir(n) + '/truth.json'))
    tr = None
    if b:
        d = b.get('refractory_tracking')
        if d:
            tr = (d['seconds'], d['standard_error'], d['bound_s'])
    for k in ('ct_on', 'ct_off'):
        tv = t['values'][k]

        def cov(d):
            if d is None:
                return 'err', None, None
            v = d.get(k)
            ci = d.get(k + '_ci95')
            if v is None:
                return 'nd', None, None
            return ('ok' if ci[0] <= tv <= ci[1] else 'MISS'), (ci[1] - ci[0]) / tv, v

        ca, wa, va = cov(a)
        cb, wb, vb = cov(b)
        s = stats.setdefault(k, {'a': {}, 'b': {}, 'wa': [], 'wb': []})
        s['a'][ca] = s['a'].get(ca, 0) + 1
        s['b'][cb] = s['b'].get(cb, 0) + 1
        if wa is not None and wb is not None:
            s['wa'].append(wa)
            s['wb'].append(wb)
        if ca != cb or (wa and wb and abs(wb / wa - 1) > 0.02) or (va and vb and abs(vb - va) > value_change):
            trs = '' if tr is None else f" T {tr[0]*1e3:.3f}+-{tr[1]*1e3:.3f} ms (bound {tr[2]*1e3:.3f})"
            values = '' if value_change == float('inf') else f" value {va if va is None else round(va, 3)} -> {vb if vb is None else round(vb, 3)}"
            print(f"{n} {t['generator']:9s} {k:6s} truth {tv:.3f} {ca}->{cb}{values} rel.width {wa if wa is None else round(wa, 3)} -> {wb if wb is None else round(wb, 3)}{trs}")
for k, s in stats.items():
    print(k, 'before', s['a'], 'after', s['b'], 'median rel width', round(statistics.median(s['wa']), 3), '->', round(statistics.median(s['wb']), 3), 'n', len(s['wa']))
