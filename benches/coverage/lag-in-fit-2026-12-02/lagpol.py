import numpy as np, sys
from PIL import Image
def load(p):
    a=np.loadtxt(p,skiprows=1)
    return a[:,0],a[:,1].astype(int),a[:,2].astype(int),a[:,3].astype(int)
case=sys.argv[1]; sims=sys.argv[2:]
W=int(open(case+'/events.txt').readline().split()[0])
frames=[l.split() for l in open(case+'/images.txt')]
ft=np.array([float(t) for t,_ in frames])
imgs=np.stack([np.asarray(Image.open(case+'/'+f)).astype(float) for _,f in frames])
t,x,y,p=load(case+'/events.txt')
k=np.clip(np.searchsorted(ft,t)-1,0,len(ft)-2)
dn=0.5*(imgs[k,y,x]+imgs[k+1,y,x])
edges=[0,10,20,40,80,160,256]
for s in sims:
    ts,xs,ys,ps=load(s+'/events.txt')
    key_r=(y*W+x)*2+p; key_s=(ys*W+xs)*2+ps
    order=np.lexsort((ts,key_s)); ks=key_s[order]; tss=ts[order]
    comb_s=ks*10.0+tss; comb_r=key_r*10.0+t
    i=np.searchsorted(comb_s,comb_r)
    best=np.full(len(t),np.inf)
    for j in (i-1,i):
        ok=(j>=0)&(j<len(comb_s)); jj=np.clip(j,0,len(comb_s)-1)
        same=ok&(ks[jj]==key_r)
        d=np.where(same,t-tss[jj],np.inf)
        best=np.where(np.abs(d)<np.abs(best),d,best)
    print(s)
    for a,b in zip(edges,edges[1:]):
        row=[]
        for pol in (0,1):
            m=(dn>=a)&(dn<b)&(np.abs(best)<0.1)&(p==pol)
            row.append(f"{'ON' if pol else 'OFF'} {np.median(best[m])*1e3 if m.sum()>50 else float('nan'):+.2f} ms n={m.sum()}")
        print(f"  {a}-{b} DN", *row)
