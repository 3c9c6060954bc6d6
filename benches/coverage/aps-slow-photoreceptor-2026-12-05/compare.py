"""Coverage of `estimate aps` before and after the slow-photoreceptor check, on the kept
draws of the aps survey: BEFORE and AFTER are directories of `SET.CASE.json` outputs (the
runs of `run.sh`), CASES maps each SET to its kept-case directory (with `truth.json`).

usage: python3 compare.py BEFORE AFTER [ALL_AFTER] > table.txt
  ALL_AFTER: the after-run of every draw (for the detection table); BEFORE/AFTER may hold
  only the draws where the check resolved a cutoff (the others are the same by construction).
"""
import collections, glob, json, os, sys

CASES = {'cases': '/work/s65/cases', 'fresh10k-cases': '/work/s66/fresh10k-cases',
         'measured-cases': '/work/s67/measured-cases', 'fresh11k-cases': '/work/s68/fresh11k-cases',
         'peer11k-cases': '/work/s68/peer11k-cases'}


def load(path):
    try:
        return json.load(open(path))
    except Exception:
        return None


def truth_of(name):
    s, case = name.split('.', 1)
    return json.load(open(f'{CASES[s]}/{case}/truth.json'))


def interval(j, key):
    if j is None or j.get(key) is None or j.get(key + '_ci95') is None:
        return None
    lo, hi = j[key + '_ci95']
    return j[key], (lo if lo is not None else 0.0), (hi if hi is not None else float('inf'))


def status(iv, t):
    if iv is None:
        return 'nd'
    return 'Y' if iv[1] <= t <= iv[2] else 'N'


before_dir, after_dir = sys.argv[1], sys.argv[2]
all_dir = sys.argv[3] if len(sys.argv) > 3 else after_dir
names = sorted(os.path.basename(f)[:-5] for f in glob.glob(f'{after_dir}/*.json')
               if os.path.exists(f'{before_dir}/' + os.path.basename(f)))
count = collections.Counter()
widen = []
rows = []
for name in names:
    b, a = load(f'{before_dir}/{name}.json'), load(f'{after_dir}/{name}.json')
    t = truth_of(name)
    slow = (a or {}).get('photoreceptor_slow')
    for key in ('ct_on', 'ct_off'):
        ib, ia = interval(b, key), interval(a, key)
        sb, sa = status(ib, t['values'][key]), status(ia, t['values'][key])
        count[(sb, sa)] += 1
        if ib and ia and ib[1] > 0:
            widen.append(((ia[2] / ia[1]) / (ib[2] / ib[1]), 'bandwidth' in t['effects']))
        rows.append((name, key, t['generator'], t['family'], t['values'].get('cutoff_hz'),
                     slow and slow['check']['cutoff_hz'], slow and slow['check']['significance'],
                     slow and slow['resimulated_thresholds'], t['values'][key], ib, ia, sb, sa))
print('polarity-cases (before, after):', dict(count))
for bw in (True, False):
    ws = sorted(w for w, has in widen if has == bw)
    if ws:
        print(f"interval hi/lo ratio after/before, {'with' if bw else 'without'} bandwidth in the truth:"
              f" median {ws[len(ws) // 2]:.2f}, max {ws[-1]:.2f} ({len(ws)} polarity-cases)")
print()
print('| draw | pol | generator | family | true cutoff (Hz at white) | found | SE | truth | before | after |')
print('|---|---|---|---|---|---|---|---|---|---|')
fmt = lambda iv, s: '-' if iv is None else f'{iv[0]:.3f} [{iv[1]:.3f}, {iv[2]:.3f}] {s}'
for r in rows:
    if r[11] != r[12] or (r[9] and r[10] and (r[9][1], r[9][2]) != (r[10][1], r[10][2])):
        print(f'| {r[0]} | {r[1][3:]} | {r[2]} | {r[3]} | {r[4] and round(r[4], 1)} | {r[5]} | {r[6] and round(r[6], 1)} |'
              f' {r[8]:.3f} | {fmt(r[9], r[11])} | {fmt(r[10], r[12])} |')
# detection against the truth over every draw
det = collections.Counter()
for f in glob.glob(f'{all_dir}/*.json'):
    name = os.path.basename(f)[:-5]
    j = load(f)
    if j is None:
        continue
    t = truth_of(name)
    det[(t['generator'], 'bandwidth' in t['effects'], bool(j.get('photoreceptor_slow')))] += 1
print()
print('detection (generator, bandwidth in the truth, check resolved a cutoff): draws')
for k in sorted(det):
    print(' ', k, det[k])
