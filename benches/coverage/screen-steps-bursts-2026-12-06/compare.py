# compare.py: the table of README.md, from before.compact.jsonl, steps.compact.jsonl and bursts.jsonl (run in this folder)
import json,sys,glob,os
def load(p):
    out={}
    for l in open(p):
        r=json.loads(l)
        if r.get('method')=='screen': out[r['case']['id']]=r
    return out
BURSTS={json.loads(l)['case']:json.loads(l) for l in open('bursts.jsonl')}
B=load('before.compact.jsonl'); A=load('steps.compact.jsonl')
def f(x,t):
    if x.get('status')!='interval': return '%-26s'%('n/d' if x.get('status')=='not_determinable' else x.get('status'))
    return '%.3f [%.2f, %.2f] %-4s'%(x['value'],x['lo'],x['hi'],'' if x['lo']<=t<=x['hi'] else 'MISS')
def fb(d,key,t):
    if d is None: return 'failed'
    v=d.get(key)
    if v is None: return 'n/d'
    lo,hi=d[key+'_ci95']; lo=lo or 0
    return '%.3f [%.2f, %.2f] %s'%(v,lo,hi,'' if lo<=t<=(hi if hi is not None else 9e9) else 'MISS')
rows=[]
for k in sorted(A, key=lambda k:int(k.split('-')[1])):
    a=A[k]; b=B.get(k); c=a['case']; p=c['params']; peer=c['peer']['params']
    refr = peer.get('refractory_period_ns',0)/1e3 if c['generator']=='esim' else (peer.get('ref_us') if c['generator']=='iebcs' else 0)
    bj=BURSTS.get(k); fpath=k
    for key,name in (('ct_on','ON'),('ct_off','OFF')):
        t=p[key]
        rows.append('| %s | %s | %s | %.0f | %s | %.3f | %s | %s | %s |'%(k.split('-')[1], c['generator'], name, p['display']['refresh_hz'], '%.0f'%refr if refr else '0', t, f(b['reported'].get(key,{'status':b['outcome']['status']}),t) if b else '', f(a['reported'].get(key,{'status':a['outcome']['status']}),t), fb(bj,key,t)))
print('| draw | generator | | refresh Hz | refractory us | truth | before (cross-fade) | steps | steps + bursts |')
print('|---|---|---|---|---|---|---|---|---|')
print('\n'.join(rows))
