# compare.txt: python3 compare.py AFTER/results.jsonl BEFORE/results.jsonl... (full coverage results, with each fit output)
# (this study's compare.txt predates the "added" column and the open-ended intervals; ../refractory-brightness-2026-12-02/compare.txt is made by this version)
import json,sys
def load(fs):
    d={}
    for f in fs:
        for l in open(f):
            r=json.loads(l)
            if r['method']=='fit': d[r['case']['id']]=r
    return d
after=load([sys.argv[1]]); before=load(sys.argv[2:])
keys=('ct_on','ct_off','ct_sigma','cutoff_hz','shot_noise_rate_hz','refractory_s','leak_rate_hz','hot_pixel_fraction')
for cid,a in after.items():
    b=before.get(cid); t=a['truth']['values']
    print(cid, a['case']['family'], 'speed %.0f'%a['case']['speed_px_s'], 'truth', {k:round(t[k],4) for k in keys if t.get(k)})
    for name,r in (('before',b),('after',a)):
        if not r: print('  ',name,'-'); continue
        rep=r.get('reported') or {}
        o=r['outcome'].get('output') or {}
        u=o.get('uncertainties',{})
        parts=[]
        for k in keys:
            if k in u:
                # an open end (null) is printed as nan below and inf above
                lo,hi=u[k].get('ci95',[None,None]); v=u[k]['value']; tv=t.get(k,0)
                lo=float('nan') if lo is None else lo; hi=float('inf') if hi is None else hi
                covered=(lo<=tv or lo!=lo) and tv<=hi
                parts.append('%s %.3g [%.3g,%.3g]%s'%(k,v,lo,hi,'' if covered else ' MISS'))
        print('  ',name,'%.0fs'%r['seconds'], '; '.join(parts), 'added', r.get('effects_added'))
