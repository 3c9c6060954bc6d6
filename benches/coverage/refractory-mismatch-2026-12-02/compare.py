"""Compares the fit's results of two coverage runs draw by draw.

Usage: python3 compare.py BEFORE/results.compact.jsonl AFTER/results.compact.jsonl

Prints, per draw run in both, the seconds, the effects added, and every reported
parameter whose value or coverage changed ("!" marks an interval that misses the truth),
then each parameter's covered / determinable before and after.
"""
import json,sys
def load(p):
    d={}
    for l in open(p):
        r=json.loads(l)
        if r['method']!='fit': continue
        cid=r['case']['id'] if 'case' in r and isinstance(r['case'],dict) else r.get('case_id')
        d[cid]=r
    return d
a=load(sys.argv[1]); b=load(sys.argv[2])
keys=['ct_on','ct_off','ct_sigma','refractory_s','cutoff_hz','shot_noise_rate_hz','hot_pixel_fraction','leak_rate_hz']
def cov(r,k):
    t=r['truth']['values'].get(k); v=r['reported'].get(k,{})
    if v.get('status')!='interval' or t is None: return None
    lo,hi=v.get('lo'),v.get('hi')
    return ((lo is None or lo<=t) and (hi is None or t<=hi)), v['value'], t
tot={}
for cid in sorted(b):
    if cid not in a: continue
    ra,rb=a[cid],b[cid]
    line=[]
    for k in keys:
        ca,cb=cov(ra,k),cov(rb,k)
        for tag,c in (('a',ca),('b',cb)):
            if c is not None:
                tot.setdefault((k,tag),[0,0]); tot[(k,tag)][0]+=c[0]; tot[(k,tag)][1]+=1
        if ca!=cb and (ca is None or cb is None or ca[0]!=cb[0] or abs(ca[1]-cb[1])>1e-9):
            line.append('%s: %s -> %s'%(k, 'n/a' if ca is None else '%.4g%s'%(ca[1],'' if ca[0] else '!'), 'n/a' if cb is None else '%.4g%s (t %.4g)'%(cb[1],'' if cb[0] else '!',cb[2])))
    ea,eb=ra['effects_added'],rb['effects_added']
    print(cid, '%.0f->%.0fs'%(ra['seconds'],rb['seconds']), ea if ea==eb else '%s -> %s'%(ea,eb), '; '.join(line))
for k in keys:
    print(k, 'before %s/%s'%tuple(tot.get((k,'a'),[0,0])), 'after %s/%s'%tuple(tot.get((k,'b'),[0,0])))
print('time', sum(a[c]['seconds'] for c in b if c in a), sum(b[c]['seconds'] for c in b if c in a))
