import json,math,sys
import os
rows=json.load(open(sys.argv[1])); M=0.37; MDIM=float(os.environ.get('MDIM','0.37'))
def need(r):
    v=math.exp(r['err'])*r['truth']
    se=r['se']/v; sysl=r['sys']/v
    m=MDIM if r['dn']<20 else M
    other2=max(sysl**2-m**2,0)
    if r['lo']<=0 and r['err']>0: return 0.0
    if r['hi']==None or (isinstance(r['hi'],float) and math.isinf(r['hi'])) and r['err']<0: return 0.0
    z=abs(r['err'])/1.959964
    return math.sqrt(max(z*z-se*se-other2,0))
def cover(sel,s):
    c=0
    for r in sel:
        c+= need(r)<=s+1e-12
    return c
for name,sel in (('dim',[r for r in rows if r['dn']<20]),('bright',[r for r in rows if r['dn']>=20])):
    ns=sorted(need(r) for r in sel)
    k=math.ceil(0.95*len(ns))-1
    print(name,'n',len(sel),'covered at 0.37',cover(sel,0.37), 'term for 95%%: %.3f'%(ns[k] if ns else float('nan')), 'quantiles', [round(ns[int(q*(len(ns)-1))],2) for q in (0.5,0.8,0.9,0.95)] if ns else None)
if len(sys.argv)>2:
    s=float(sys.argv[2])
    for name,sel in (('dim',[r for r in rows if r['dn']<20]),('bright',[r for r in rows if r['dn']>=20])):
        print(name,'at',s,'covered',cover(sel,s),'of',len(sel))
