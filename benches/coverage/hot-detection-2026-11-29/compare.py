import json,sys,math
def load(p):
    d={}
    for l in open(p):
        r=json.loads(l); d[r['case']['seed']]=r
    return d
a=load(sys.argv[1]); b=load(sys.argv[2])
def share(curve,rate):
    if not curve: return 0.5
    if rate<=curve[0][0]: return curve[0][1] if rate>0 else 0
    for (r0,p0),(r1,p1) in zip(curve,curve[1:]):
        if rate<=r1: return p0+math.log(rate/r0)/math.log(r1/r0)*(p1-p0)
    return curve[-1][1]
def show(r,k,curve=None):
    rep=r.get('reported',{}).get(k,{})
    if rep.get('status')!='interval': return rep.get('status','-'),None,None
    t=r['truth']['values'].get(k,0.0)
    if k=='hot_pixel_fraction' and curve is not None: t*=min(1,2*share(curve,r['truth']['values'].get('hot_pixel_rate_hz',0.0)))
    lo=rep['lo'] if rep['lo'] is not None else -1e300; hi=rep['hi'] if rep['hi'] is not None else 1e300
    ok=lo<=t<=hi
    return '%.3g [%.3g, %.3g] %s'%(rep['value'],rep['lo'] or 0,rep['hi'] or 0,'ok' if ok else 'MISS'),ok,t
tot={}
for s in sorted(b):
    if s not in a: continue
    p=b[s]['case']['params']
    curve=b[s].get('hot_detection')
    line=[]
    for k in ('hot_pixel_fraction','hot_pixel_rate_hz'):
        sa,oka,_=show(a[s],k); sb,okb,tb=show(b[s],k,curve)
        if not p.get('hot_pixel_fraction'): oka=okb=None
        for tag,ok in (('a',oka),('b',okb)):
            if ok is not None: tot.setdefault((k,tag),[0,0]); tot[(k,tag)][0]+=ok; tot[(k,tag)][1]+=1
        line.append(f"{k[10:]}: {sa} -> {sb}" + (f" (scored truth {tb:.3g})" if tb is not None and k=='hot_pixel_fraction' else ''))
    half=None
    if curve:
        print(s,'true frac',p.get('hot_pixel_fraction'),'rate',p.get('hot_pixel_rate_hz'),'p(true rate)', round(share(curve,p.get('hot_pixel_rate_hz') or 0),3))
    else:
        print(s,'true frac',p.get('hot_pixel_fraction'),'rate',p.get('hot_pixel_rate_hz'))
    for x in line: print('   ',x)
for k,v in sorted(tot.items()): print(k, '%d/%d'%tuple(v))
