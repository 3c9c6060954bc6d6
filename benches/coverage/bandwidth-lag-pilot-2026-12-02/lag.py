import numpy as np, sys
from PIL import Image
def load(p):
    a=np.loadtxt(p,skiprows=1)
    return a[:,0],a[:,1].astype(int),a[:,2].astype(int),a[:,3].astype(int)
case=sys.argv[1]; sims=sys.argv[2:]
frames=[l.split() for l in open(case+'/images.txt')]
ft=np.array([float(t) for t,_ in frames])
imgs=np.stack([np.asarray(Image.open(case+'/'+f)).astype(float) for _,f in frames])
def dn_at(t,x,y):
    k=np.clip(np.searchsorted(ft,t)-1,0,len(ft)-2)
    return 0.5*(imgs[k,y,x]+imgs[k+1,y,x])
t,x,y,p=load(case+'/events.txt')
W=240
edges=[0,10,20,40,80,160,256]
for s in sims:
    ts,xs,ys,ps=load(s+'/events.txt')
    key_r=(y*W+x)*2+p; key_s=(ys*W+xs)*2+ps
    order=np.lexsort((ts,key_s)); ks=key_s[order]; tss=ts[order]
    # nearest sim event of same key
    # search: combined key*1e3 + t (t<~2s)
    comb_s=ks*10.0+tss; comb_r=key_r*10.0+t
    i=np.searchsorted(comb_s,comb_r)
    best=np.full(len(t),np.inf)
    for j in (i-1,i):
        ok=(j>=0)&(j<len(comb_s))
        jj=np.clip(j,0,len(comb_s)-1)
        same=ok&(ks[jj]==key_r)
        d=np.where(same,t-tss[jj],np.inf)
        best=np.where(np.abs(d)<np.abs(best),d,best)
    good=np.abs(best)<0.1
    dn=dn_at(t,x,y)
    print(s, 'matched %.2f'%good.mean())
    for a,b in zip(edges[:-1],edges[1:]):
        m=good&(dn>=a)&(dn<b)
        if m.sum()<50: continue
        o=best[m]*1e3
        print('  %3d-%3d DN n=%6d median %+6.2f ms  mean %+6.2f  frac>0 %.2f'%(a,b,m.sum(),np.median(o),o.mean(),(o>0).mean()))
