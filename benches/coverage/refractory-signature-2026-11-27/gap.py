import numpy as np,sys,json
for s in sys.argv[1:]:
    d=f'work-{s}/case-{s}'
    a=np.loadtxt(f'{d}/events.txt',skiprows=0,comments='#') if False else None
    rows=[l.split() for l in open(f'{d}/events.txt') if not l.startswith('#')]
    rows=[r for r in rows if len(r)==4]
    a=np.array(rows,dtype=float)
    t=(a[:,0]*1e6).round().astype(np.int64); x=a[:,1].astype(int); y=a[:,2].astype(int)
    pix=y*10000+x
    o=np.lexsort((t,pix)); t=t[o]; pix=pix[o]
    same=pix[1:]==pix[:-1]; iv=(t[1:]-t[:-1])[same]
    tr=json.load(open(f'{d}/truth.json'))['values']
    q=np.quantile(iv,[0.001,0.005,0.01,0.02,0.05,0.1])
    h,e=np.histogram(iv[iv<20000],bins=40,range=(0,20000))
    print(s,'refr %.0f us jitter %.0f'%(tr['refractory_s']*1e6,tr['timestamp_jitter_s']*1e6),'n',len(iv),'q',q.astype(int), 'peak bin',e[h.argmax()])
    # per-pixel minimum intervals
    starts=np.r_[0,np.nonzero(pix[1:]!=pix[:-1])[0]+1]
    ivall=np.r_[np.diff(t),0]; ok=np.r_[pix[1:]==pix[:-1],False]
    mins=[]
    for a,b in zip(starts,np.r_[starts[1:],len(t)]):
        v=ivall[a:b][ok[a:b]]
        if len(v)>=3: mins.append(v.min())
    mins=np.array(mins)
    print('   per-pixel min (>=3 iv): n',len(mins),'q05/10/25',np.quantile(mins,[0.05,0.1,0.25]).astype(int))
