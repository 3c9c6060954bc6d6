# compare.py: the table of README.md, from ../screen-steps-bursts-2026-12-06 (the draws'
# truth and the fixed-floor bursts check) and bursts-noise.jsonl (run in this folder)
import json
here = '../screen-steps-bursts-2026-12-06/'
cases = {}
for l in open(here + 'steps.compact.jsonl'):
    r = json.loads(l)
    if r.get('method') == 'screen':
        cases[r['case']['id']] = r['case']
old = {json.loads(l)['case']: json.loads(l) for l in open(here + 'bursts.jsonl')}
new = {json.loads(l)['case']: json.loads(l) for l in open('bursts-noise.jsonl')}

def shown(d, key, t):
    if d is None:
        return 'failed'
    v = d.get(key)
    if v is None:
        return 'n/d'
    lo, hi = d[key + '_ci95']
    lo = lo or 0
    ok = lo <= t <= (hi if hi is not None else 9e9)
    return '%.3f [%.2f, %.2f]%s' % (v, lo, hi, '' if ok else ' MISS')

def shares(d, side):
    b = (d or {}).get('bursts')
    if not b:
        return ''
    r, m = b['recorded'][side], b['model'][side]
    z = r.get('shortfall_z')
    return '%.1f / %.1f %%, z %s' % (100 * r['share'], 100 * m['share'], 'inf' if z is None else '%.1f' % z)

tally = {'old': [0, 0, 0], 'new': [0, 0, 0]}
print('| draw | generator | | truth | repeats recorded / model, shortfall z | fixed 10 % floor | noise-weighed |')
print('|---|---|---|---|---|---|---|')
for k in sorted(cases, key=lambda k: int(k.split('-')[1])):
    c = cases[k]
    for key, side, name in (('ct_on', 'on', 'ON'), ('ct_off', 'off', 'OFF')):
        t = c['params'][key]
        a, b = shown(old.get(k), key, t), shown(new.get(k), key, t)
        for which, s in (('old', a), ('new', b)):
            tally[which][0 if 'MISS' in s else 1 if '[' in s else 2] += 1
        print('| %s | %s | %s | %.3f | %s | %s | %s |' % (k.split('-')[1], c['generator'], name, t, shares(new.get(k), side), a, b))
for which, (miss, cov, nd) in tally.items():
    print('\n%s: covered %d / %d determinable, %d not determinable' % (which, cov, cov + miss, nd))
