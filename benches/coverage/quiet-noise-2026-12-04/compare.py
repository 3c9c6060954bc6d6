import json,sys
new={}
for l in open('benches/coverage/quiet-noise-2026-12-04/results.compact.jsonl'):
    r=json.loads(l); new[r['case']['seed']]=r
old={}
for st in ['fresh-7001-7040-2026-12-04','fresh-8001-8030-2026-12-04','fresh-9001-9030-2026-12-04']:
    for l in open(f'benches/coverage/{st}/results.compact.jsonl'):
        r=json.loads(l)
        if r.get('method')=='fit': old[r['case']['seed']]=r
def f(v):
    if not v: return '-'
    if v.get('status')=='interval': return '%.3f[%s,%s]'%(v['value'], None if v['lo'] is None else round(v['lo'],3), None if v['hi'] is None else round(v['hi'],3))
    return v.get('status','')[:6]
def cov(v,t):
    if not v or v.get('status')!='interval': return None
    return (v['lo'] is None or v['lo']<=t) and (v['hi'] is None or t<=v['hi'])
tot={'old':[0,0],'new':[0,0]}
for k in ['shot_noise_rate_hz','leak_rate_hz','ct_on','ct_off','ct_sigma']:
  for which,d in (('old',old),('new',new)):
    a=n=0
    for s in sorted(new):
        if s not in d: continue
        t=d[s]['truth']['values'].get(k, 0.0)
        c=cov(d[s]['reported'].get(k),t)
        if c is not None: a+=c; n+=1
    print(k, which, f'{a}/{n}')
for s in sorted(new):
    t=new[s]['truth']['values']
    o=old.get(s,{}).get('reported',{})
    print(s, 'SN %.3f'%t.get('shot_noise_rate_hz',0), f(o.get('shot_noise_rate_hz')).ljust(26), '->', f(new[s]['reported'].get('shot_noise_rate_hz')).ljust(26), '| LK %.3f'%t.get('leak_rate_hz',0), f(o.get('leak_rate_hz')), '->', f(new[s]['reported'].get('leak_rate_hz')), new[s]['outcome']['status'], round(old.get(s,{}).get('seconds',0)), '->', round(new[s]['seconds']))
