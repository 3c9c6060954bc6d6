# Per intensity bin (the frames' mean DN over the event's interval) and polarity: the median
# offset of recorded events from the nearest simulated event of the same pixel and polarity,
# within GAP seconds; "all" pairs every event, "onset" only events whose pixel gave no event
# of that polarity in the GAP before (burst starts), recorded and simulated alike.
# usage: python3 lagons.py CASE_DIR GAP_S SIM_DIR...   (needs numpy, pillow; a CASE_DIR holds
# events.txt, images.txt and the images; SIM_DIR the events.txt of `ctcal simulate --frames`)
import numpy as np, sys
from PIL import Image
def load(p):
    a=np.loadtxt(p,skiprows=1)
    return a[:,0],a[:,1].astype(int),a[:,2].astype(int),a[:,3].astype(int)
case=sys.argv[1]; gap=float(sys.argv[2]); sims=sys.argv[3:]
W=int(open(case+'/events.txt').readline().split()[0])
frames=[l.split() for l in open(case+'/images.txt')]
ft=np.array([float(t) for t,_ in frames])
imgs=np.stack([np.asarray(Image.open(case+'/'+f)).astype(float) for _,f in frames])
def onset(t,key):
    o=np.lexsort((t,key)); ks=key[o]; ts=t[o]
    first=np.ones(len(t),bool); first[1:]=(ks[1:]!=ks[:-1])|((ts[1:]-ts[:-1])>gap)
    m=np.zeros(len(t),bool); m[o]=first; return m
t,x,y,p=load(case+'/events.txt')
k=np.clip(np.searchsorted(ft,t)-1,0,len(ft)-2)
dn=0.5*(imgs[k,y,x]+imgs[k+1,y,x])
key_r=(y*W+x)*2+p
on_r=onset(t,key_r)
edges=[0,10,20,40,80,160,256]
def pair(tr,kr,ts,ks):
    o=np.lexsort((ts,ks)); ks=ks[o]; ts=ts[o]
    comb_s=ks*10.0+ts; comb_r=kr*10.0+tr
    i=np.searchsorted(comb_s,comb_r); best=np.full(len(tr),np.inf)
    for j in (i-1,i):
        ok=(j>=0)&(j<len(comb_s)); jj=np.clip(j,0,len(comb_s)-1)
        same=ok&(ks[jj]==kr); d=np.where(same,tr-ts[jj],np.inf)
        best=np.where(np.abs(d)<np.abs(best),d,best)
    return best
for s in sims:
    ts,xs,ys,ps=load(s+'/events.txt'); key_s=(ys*W+xs)*2+ps
    on_s=onset(ts,key_s)
    b_all=pair(t,key_r,ts,key_s)
    b_on=np.full(len(t),np.inf); b_on[on_r]=pair(t[on_r],key_r[on_r],ts[on_s],key_s[on_s])
    print(s)
    for a,b in zip(edges,edges[1:]):
        row=[]
        for name,best in (('all',b_all),('onset',b_on)):
            for pol in (0,1):
                m=(dn>=a)&(dn<b)&(np.abs(best)<gap)&(p==pol)
                row.append(f"{name} {'ON' if pol else 'OFF'} {np.median(best[m])*1e3 if m.sum()>50 else float('nan'):+6.2f} n={m.sum():5d}")
        print(f"  {a:3d}-{b:3d}", ' | '.join(row))
