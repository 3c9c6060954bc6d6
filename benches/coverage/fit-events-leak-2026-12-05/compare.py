import json,glob,os
old={}
for l in open('/work/s69/fresh12k-balance2/results.jsonl'):
    r=json.loads(l)
    if r.get('method')!='fit_events': continue
    cid=r['case']['id'] if isinstance(r.get('case'),dict) else r.get('case')
    old[cid]=r
cov={'old':[0,0],'new':[0,0]}; changed=0
for f in sorted(glob.glob('/work/s70/fe/case-*.json')):
    cid=os.path.basename(f)[:-5]
    tr=json.load(open(f'/work/s69/fresh12k-cases/{cid}/truth.json'))['values']
    d=json.load(open(f)); u=d['uncertainties'].get('leak_rate_hz'); w=d['why'].get('leak_rate_hz','')
    o=old.get(cid,{}).get('reported',{}).get('leak_rate_hz')
    t=tr.get('leak_rate_hz',0)
    def inside(lo,hi): return (lo is None or lo<=t) and (hi is None or t<=hi)
    ns=''
    if u and u.get('ci95'):
        lo,hi=u['ci95']; c=inside(lo,hi); cov['new'][0]+=c; cov['new'][1]+=1; ns=f'new [{lo},{hi}] {"Y" if c else "N"}'
    os_=''
    if o and o.get('status')=='interval':
        c=inside(o['lo'],o['hi']); cov['old'][0]+=c; cov['old'][1]+=1; os_=f"old {o['value']:.3f} [{o['lo']},{o['hi']}] {'Y' if c else 'N'}"
    if ns or os_:
        print(cid, 'truth', t, '|', os_, '|', ns, '| scene' if 'scene fires' in w else '')
print(cov)
