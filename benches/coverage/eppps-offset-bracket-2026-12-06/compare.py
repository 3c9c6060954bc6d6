"""compare_eppps.py BEFORE AFTER CASES: estimate eppps before/after against each draw's truth."""
import json,sys,os
before,after,cases=sys.argv[1:4]
def load(d,n):
    try: return json.load(open(f'{d}/{n}.json'))
    except Exception: return None
def cov(e,t,k):
    if e is None or e.get(k) is None: return 'nd', None
    ci=e.get(k+'_ci95') or [None,None]
    lo=ci[0] if ci[0] is not None else 0.0; hi=ci[1] if ci[1] is not None else float('inf')
    return ('ok' if lo<=t<=hi else 'MISS'), f"{e[k]:.3f} [{lo:.3f}, {hi:.3f}]"
tot={'before':{'ok':0,'MISS':0,'nd':0},'after':{'ok':0,'MISS':0,'nd':0}}
for c in open(cases).read().split():
    n=os.path.basename(c); truth=json.load(open(c+'/truth.json'))
    t=truth.get('values',truth)
    b,a=load(before,n),load(after,n)
    for k in ['ct_on','ct_off']:
        sb,vb=cov(b,t[k],k); sa,va=cov(a,t[k],k)
        tot['before'][sb]+=1; tot['after'][sa]+=1
        mark='' if vb==va else ' *'
        print(f"{n:11s} {k:6s} truth {t[k]:.3f}: {sb:4s} {vb}  ->  {sa:4s} {va}{mark}")
print(tot)
