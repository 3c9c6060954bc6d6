"""eppps before/after: coverage of Cp/Cn over polarity-cases read through frames, which
draws the slow-photoreceptor check fired on, and interval widths (hi/lo in ln)."""
import json, sys, math
def load(path):
    out = {}
    for l in open(path):
        r = json.loads(l)
        out[r['case']['id']] = r
    return out
before, after = load(sys.argv[1]), load(sys.argv[2])
rows = []
for cid, a in sorted(after.items()):
    b = before.get(cid)
    if not b or not a.get('truth'): continue
    out = (a.get('outcome') or {})
    js = out.get('json') if isinstance(out, dict) else None
    for key in ('ct_on', 'ct_off'):
        t = a['truth']['values'].get(key)
        ra, rb = a['reported'].get(key, {}), b['reported'].get(key, {})
        if ra.get('status') != 'interval' or rb.get('status') != 'interval': continue
        cov = lambda r: (r.get('lo') or 0) <= t <= (r.get('hi') or math.inf)
        w = lambda r: math.log((r.get('hi') or math.inf) / max(r.get('lo') or 1e-9, 1e-9))
        rows.append((cid, key, t, rb, ra, cov(rb), cov(ra), w(rb), w(ra), a['truth']['values'].get('cutoff_hz')))
n = len(rows)
print(f"polarity-cases {n}: covered before {sum(r[5] for r in rows)}, after {sum(r[6] for r in rows)}")
changed = [r for r in rows if r[3] != r[4]]
print(f"changed {len(changed)} polarity-cases on {len(set(r[0] for r in changed))} draws")
for r in changed:
    print(f"  {r[0]} {r[1]} truth {r[2]:.3f} cutoff {r[9]}: {r[3]['value']:.3f} [{r[3]['lo']:.3f}, {r[3]['hi']:.3f}] -> [{r[4]['lo']:.3f}, {r[4]['hi']:.3f}] covered {r[5]}->{r[6]} width x{math.exp(r[8]-r[7]) if math.isfinite(r[8]) else 'inf':}")
lost = [r for r in rows if r[5] and not r[6]]
gained = [r for r in rows if r[6] and not r[5]]
print("gained", [(r[0], r[1]) for r in gained]); print("lost", [(r[0], r[1]) for r in lost])
misses = [r for r in rows if not r[6]]
print("misses after", [(r[0], r[1], round(r[2],3), round(r[4]['value'],3), r[9]) for r in misses])
# value errors where the values moved (the low-passed reading taken)
moved = [r for r in rows if r[3]['value'] != r[4]['value']]
if moved:
    import statistics as st
    eb = [abs(math.log(r[3]['value'] / r[2])) for r in moved]
    ea = [abs(math.log(r[4]['value'] / r[2])) for r in moved]
    print(f"values moved on {len(moved)} polarity-cases: median |ln(value/truth)| {st.median(eb):.3f} -> {st.median(ea):.3f}, mean {st.mean(eb):.3f} -> {st.mean(ea):.3f}, closer on {sum(a < b for a, b in zip(ea, eb))}")
allb = [abs(math.log(r[3]['value'] / r[2])) for r in rows]
alla = [abs(math.log(r[4]['value'] / r[2])) for r in rows]
import statistics as st
print(f"all {len(rows)}: median |ln error| {st.median(allb):.3f} -> {st.median(alla):.3f}; median ln width {st.median([r[7] for r in rows]):.3f} -> {st.median([r[8] for r in rows]):.3f}")
