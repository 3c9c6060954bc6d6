import json,glob,os,collections,sys
D=sys.argv[1]
T=collections.Counter(); miss=[]; G=collections.Counter()
for p in sorted(glob.glob(D+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    try: a=json.load(open(p))
    except: T['failed']+=1; continue
    t=json.load(open(f'cases-all/{n}/truth.json'))
    for k in ('ct_on','ct_off'):
        tr=t['values'].get(k)
        if 'uncertainties' in a:
            u=a['uncertainties'].get(k,{}); v=u.get('value') if a['params'].get(k) is not None else None; ci=u.get('ci95') if v is not None else None
        else:
            v=a.get(k); ci=a.get(k+'_ci95')
        if v is None: T[(k,'nd')]+=1; continue
        if not ci: T[(k,'noci')]+=1; continue
        lo,hi=ci; ok=(lo is None or lo<=tr) and (hi is None or tr<=hi)
        T[(k,'ok' if ok else 'MISS')]+=1; G[(t['generator'],k,'ok' if ok else 'MISS')]+=1
        if not ok: miss.append((n,t['generator'],k,round(tr,3),round(v,3),[round(x,3) if x is not None else None for x in ci]))
for k,v in sorted(T.items(),key=str): print(k,v)
for k,v in sorted(G.items()): print(k,v)
for m in miss: print(m)
