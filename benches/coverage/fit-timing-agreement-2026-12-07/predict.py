import json,glob,os,collections,math,sys
Z=1.959964
def load(p):
    try: return json.load(open(p))
    except: return None
def fitci(d,key):
    u=d.get('uncertainties',{}).get(key)
    if not u or u.get('value') is None: return None
    ci=u.get('ci95')
    if ci is None or ci[0] is None: return None
    return (u['value'],ci[0],ci[1] if ci[1] is not None else math.inf)
def timing(a,key):
    if a is None: return None
    for e in a.get('estimators',[]):
        if e['name']=='event_timing' and e.get(key) and e[key].get('value') is not None:
            v=e[key]; det=e['details']['on' if key=='ct_on' else 'off']
            return dict(v=v['value'],lo=v['ci95'][0],hi=v['ci95'][1],se=v['standard_error'],sys=v.get('systematic',0),off=det.get('offset_systematic',0))
    return None
mode=sys.argv[1]; zlim=float(sys.argv[2]) if len(sys.argv)>2 else Z
aps_dir={'cases':'aps-growth','cases17':'aps17-growth'}
T=collections.Counter(); rows=[]; widen=[]
for C,F in (('cases','fit-growth5'),('cases17','fit17-growth5')):
  for p in sorted(glob.glob(F+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    q='fit-growth6/'+n+'.json'
    if os.path.exists(q): p=q
    d=load(p)
    if d is None: continue
    a=load(f'{aps_dir[C]}/{n}.json')
    t=json.load(open(f'{C}/{n}/truth.json'))
    startnd = a is not None and a.get('ct_on') is None
    # per polarity z; reconcile both if worst > zlim
    zs={}; info={}
    for key in ('ct_on','ct_off'):
        f=fitci(d,key); tm=timing(a,key)
        info[key]=(f,tm)
        if f is None or tm is None or tm['lo']<=0 or f[1]<=0 or not math.isfinite(f[2]): continue
        if mode in ('ndonly','cind') and not startnd: continue
        fse=math.log(f[2]/f[1])/(2*Z)
        if mode in ('se','ndonly'):
            tse=math.sqrt(tm['se']**2+max(tm['sys']**2-tm['off']**2,0))/tm['v']
        else:
            tse=math.log(tm['hi']/tm['lo'])/(2*Z)
        zs[key]=abs(math.log(f[0]/tm['v']))/math.hypot(fse,tse)
    worst=max(zs.values(),default=0)
    for key in ('ct_on','ct_off'):
        f,tm=info[key]; tr=t['values'][key]
        if f is None: T[(key,'nd')]+=1; continue
        ok=f[1]<=tr<=f[2]
        if worst>zlim and key in zs:
            lo,hi=min(f[1],tm['lo']),max(f[2],tm['hi']); ok2=lo<=tr<=hi
            T[(key,'rec','ok' if ok else 'MISS','->','ok' if ok2 else 'MISS')]+=1
            widen.append(math.log(hi/lo)/math.log(f[2]/f[1]))
            if ok!=ok2 or widen[-1]>1.5: rows.append((n,t['generator'],key,round(tr,3),[round(x,3) for x in f],round(tm['v'],3),[round(tm['lo'],3),round(tm['hi'],3)],round(worst,1),ok,ok2,round(widen[-1],2)))
        else:
            T[(key,'keep','ok' if ok else 'MISS')]+=1
for r in rows: print(r)
for k,v in sorted(T.items()): print(k,v)
print('reconciled',len(widen),'median log-width ratio',sorted(widen)[len(widen)//2] if widen else None, 'n>1.5',sum(w>1.5 for w in widen))
