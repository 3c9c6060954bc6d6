# Per draw, the fit's reported parameters that differ between two coverage runs (AFTER BEFORE,
# results.compact.jsonl each[, METHOD: fit (default) or fit_events]), with the truth; !MISS
# marks an interval that misses it.
import json,math,sys
METHOD=sys.argv[3] if len(sys.argv)>3 else 'fit'
def load(p):
    d={}
    for l in open(p):
        r=json.loads(l)
        if r['method']==METHOD: d[r['case']['id']]=r
    return d
A=load(sys.argv[1]); B=load(sys.argv[2])
g=lambda x: 'open' if x is None else f"{x:.3g}"
for cid in sorted(A):
    a=A[cid]; b=B.get(cid)
    if not b: continue
    tv=a['truth']['values']
    out=[]
    for k in ('ct_on','ct_off','ct_sigma','cutoff_hz','shot_noise_rate_hz','refractory_s','leak_rate_hz','hot_pixel_fraction'):
        ra=a.get('reported',{}).get(k,{}); rb=b.get('reported',{}).get(k,{})
        def f(r):
            if r.get('status')=='interval':
                cov = (r['lo'] or 0)<=tv.get(k,0)<=(r['hi'] if r['hi'] is not None else 1e99)
                return f"{r['value']:.3g}[{g(r['lo'])},{g(r['hi'])}]{'' if cov else '!MISS'}"
            return r.get('status','-')[:8]
        if f(ra)!=f(rb): out.append(f"  {k} truth {tv.get(k,0):.3g}: {f(rb)} -> {f(ra)}")
    if out: print(cid, round(b['seconds']), '->', round(a['seconds']), 's'); print('\n'.join(out))
