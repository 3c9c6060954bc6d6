"""The fit's effect intervals where the kept effect is not separated from a look-alike:
coverage as reported (the interval reaches 0) and as it was before (the interval if the
effect is there, `ambiguities[].kept_ci95_if_present`).

usage: ambiguity.py RESULTS.jsonl [EXTRACT.jsonl]   (a coverage run's full results.jsonl;
       writes the ambiguities with their truth, intervals and reasons to EXTRACT.jsonl)
       ambiguity.py EXTRACT.jsonl                    (that extract, as committed here)
"""
import json, sys

PARAM = {'bandwidth': 'cutoff_hz', 'refractory': 'refractory_s', 'leak': 'leak_rate_hz',
         'shot_noise': 'shot_noise_rate_hz', 'mismatch': 'ct_sigma'}


def extract(path):
    """One row per ambiguity: the case, its truth, the ambiguity, the fit's intervals and reasons."""
    rows = []
    for line in open(path):
        r = json.loads(line)
        if 'outcome' not in r:  # already an extract
            rows.append(r)
            continue
        out = r['outcome'].get('output')
        for a in (out or {}).get('ambiguities', []):
            rows.append({'case': r['case']['id'], 'truth': r['truth']['values'], **a,
                         'uncertainties': out['uncertainties'], 'why': out.get('why', {})})
    return rows


def g(v):
    return 'open' if v is None else f'{v:.4g}'


def covered(lo, hi, t):
    return (lo is None or lo <= t) and (hi is None or t <= hi)


rows = extract(sys.argv[1])
if len(sys.argv) > 2:
    with open(sys.argv[2], 'w') as f:
        f.writelines(json.dumps(r) + '\n' for r in rows)
before = after = n = present = 0
print('| case | kept | look-alike | truth kept | truth look-alike | interval if present | reported | before | after |')
print('|---|---|---|---|---|---|---|---|---|')
for a in rows:
    key = PARAM[a['kept']]
    if key in a['why'] or a.get('kept_ci95_if_present') is None:
        continue  # withheld with its own reason, or no interval
    t = a['truth'].get(key) or 0.0
    u = a['uncertainties'][key]
    lo0, hi0 = a['kept_ci95_if_present']
    lo1, hi1 = u['ci95']
    b, f = covered(lo0, hi0, t), covered(lo1, hi1, t)
    n += 1; before += b; after += f; present += t > 0
    alt = a['truth'].get(a['parameter']) or 0.0
    print(f"| {a['case']} | {a['kept']} {u['value']:.4g} | {a['alternative']} {a['value']:.4g} | {t:.4g} | {alt:.4g} "
          f"| [{g(lo0)}, {g(hi0)}] | [{g(lo1)}, {g(hi1)}] | {'yes' if b else 'no'} | {'yes' if f else 'no'} |")
print(f'\nnot separated, kept effect measured: {n}; truly present: {present}; covered before {before}, after {after}')
