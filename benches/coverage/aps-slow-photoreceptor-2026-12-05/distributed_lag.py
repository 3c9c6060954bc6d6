"""Distributed-lag regression of a pixel's net event count per frame interval on the frames'
log change in that interval and the J before it, pooled over pixels (an IJRR-layout case:
events.txt, images.txt). On a pixel that follows the frames the weight sits at lag 0; a
photoreceptor much slower than the scene spreads it over later intervals.

usage: python3 distributed_lag.py CASE_DIR [J=4] [b=1.0 DN, the log offset]
"""
import numpy as np, sys
from PIL import Image
d=sys.argv[1]; J=int(sys.argv[2]) if len(sys.argv)>2 else 4; b=float(sys.argv[3]) if len(sys.argv)>3 else 1.0
lines=[l.split() for l in open(d+'/images.txt')]
ts=np.array([float(l[0]) for l in lines]); fr=np.stack([np.asarray(Image.open(d+'/'+l[1]).convert('L'),float) for l in lines])
H,W=fr.shape[1:]
L=np.log(fr+b)
ev=np.loadtxt(d+'/events.txt',skiprows=1)
t,x,y,p=ev[:,0],ev[:,1].astype(int),ev[:,2].astype(int),ev[:,3]
K=len(ts)-1
k=np.searchsorted(ts,t)-1
m=(k>=0)&(k<K)
N_on=np.zeros((K,H,W)); N_off=np.zeros((K,H,W))
np.add.at(N_on,(k[m&(p>0)],y[m&(p>0)],x[m&(p>0)]),1)
np.add.at(N_off,(k[m&(p<=0)],y[m&(p<=0)],x[m&(p<=0)]),1)
dL=np.diff(L,axis=0)
# regression of N_on - N_off on dL lags (pooled), separately positive & negative parts
rows=[];tgt=[]
for kk in range(J,K):
    X=np.stack([dL[kk-j].ravel() for j in range(J+1)],1)
    rows.append(X); tgt.append((N_on[kk]-N_off[kk]).ravel())
X=np.concatenate(rows); Y=np.concatenate(tgt)
a,res,_,_=np.linalg.lstsq(X,Y,rcond=None)
print('J',J,'coef',np.round(a,3),'sum',a.sum(),'C=1/sum',1/a.sum(), 'C0=1/a0',1/a[0])
# split ON/OFF: N_on vs positive part
Xp=np.concatenate([np.stack([np.clip(dL[kk-j],0,None).ravel() for j in range(J+1)]+[np.clip(-dL[kk-j],0,None).ravel() for j in range(J+1)],1) for kk in range(J,K)])
Yon=np.concatenate([N_on[kk].ravel() for kk in range(J,K)]); Yoff=np.concatenate([N_off[kk].ravel() for kk in range(J,K)])
aon=np.linalg.lstsq(Xp,Yon,rcond=None)[0]; aoff=np.linalg.lstsq(Xp,Yoff,rcond=None)[0]
print('ON from +dL lags',np.round(aon[:J+1],3),'Cp',1/aon[:J+1].sum(),' OFF from -dL',np.round(aoff[J+1:],3),'Cn',1/aoff[J+1:].sum())
