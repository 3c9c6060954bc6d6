"""Before/after table of the fit with frames on one set of coverage draws: per reported
parameter the intervals covering the truth, the effects claimed where the truth has none and
the noise present but not reported, then each draw's row and every reported parameter that
changed, with whether its interval covers the truth. The studies' own `compare.py` call it
with their result files. Run from the repository root:

    python3 benches/coverage/compare_fit.py AFTER BEFORE [BEFORE ...]

AFTER and each BEFORE are `results.compact.jsonl` (or full) files of `coverage --methods fit`;
the draws are AFTER's, a draw's before row the last BEFORE file that has it.
"""
import json
import sys

KEYS = ['shot_noise_rate_hz', 'leak_rate_hz', 'ct_on', 'ct_off', 'ct_sigma', 'cutoff_hz',
        'refractory_s', 'hot_pixel_fraction']


def rows(path):
    out = {}
    for line in open(path):
        r = json.loads(line)
        if r.get('method') == 'fit':
            out[r['case']['seed']] = r
    return out


new = rows(sys.argv[1])
old = {}
for path in sys.argv[2:]:
    old.update(rows(path))


def show(v):
    if not v:
        return '-'
    if v.get('status') == 'interval':
        side = lambda x: 'open' if x is None else '%.3g' % x
        return '%.3g[%s,%s]' % (v['value'], side(v['lo']), side(v['hi']))
    return v.get('status', '')[:8]


def covers(v, t):
    if not v or v.get('status') != 'interval':
        return None
    return (v['lo'] is None or v['lo'] <= t) and (v['hi'] is None or t <= v['hi'])


def claimed_where_none(v, t):
    return t == 0 and v and v.get('status') == 'interval' and (v['lo'] or 0) > 0


print('| fit with frames, %d draws | before | after |' % len(new))
print('|---|---|---|')
for k in KEYS:
    cells = []
    for d in (old, new):
        hit = n = 0
        for s in new:
            if s not in d:
                continue
            c = covers(d[s]['reported'].get(k), d[s]['truth']['values'].get(k, 0.0))
            if c is not None:
                hit += c
                n += 1
        cells.append('%d/%d' % (hit, n))
    print('| `%s` intervals covering | %s | %s |' % (k, cells[0], cells[1]))
for k in ['shot_noise_rate_hz', 'leak_rate_hz', 'refractory_s', 'cutoff_hz']:
    cells = []
    for d in (old, new):
        bad = [s for s in sorted(new) if s in d and claimed_where_none(
            d[s]['reported'].get(k), d[s]['truth']['values'].get(k, 0.0))]
        cells.append('%d %s' % (len(bad), bad))
    print('| `%s` claimed where none | %s | %s |' % (k, cells[0], cells[1]))
for k in ['shot_noise_rate_hz', 'leak_rate_hz']:
    cells = []
    for d in (old, new):
        miss = [s for s in sorted(new) if s in d
                and d[s]['truth']['values'].get(k, 0.0) > 0
                and (d[s]['reported'].get(k) or {}).get('status') != 'interval']
        cells.append('%d' % len(miss))
    print('| `%s` present, not reported | %s | %s |' % (k, cells[0], cells[1]))
print()
for s in sorted(new):
    t = new[s]['truth']['values']
    o = old.get(s, {}).get('reported', {})
    n = new[s]['reported']
    print(s, 'SN %.3f' % t.get('shot_noise_rate_hz', 0),
          show(o.get('shot_noise_rate_hz')).ljust(22), '->',
          show(n.get('shot_noise_rate_hz')).ljust(22),
          '| LK %.3f' % t.get('leak_rate_hz', 0), show(o.get('leak_rate_hz')), '->',
          show(n.get('leak_rate_hz')), '|', new[s]['outcome']['status'],
          round(old.get(s, {}).get('seconds', 0)), '->', round(new[s]['seconds']))

print()
print('every reported parameter that changed (truth: before -> after):')
for s in sorted(new):
    t = new[s]['truth']['values']
    o = old.get(s, {}).get('reported', {})
    n = new[s]['reported']
    for k in KEYS:
        if show(o.get(k)) != show(n.get(k)):
            mark = {True: 'covers', False: 'MISSES', None: ''}[covers(n.get(k), t.get(k, 0.0))]
            print(s, k, '%.4g:' % t.get(k, 0.0), show(o.get(k)), '->', show(n.get(k)), mark)
