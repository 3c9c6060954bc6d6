import json,glob,os,math,sys
B,A=sys.argv[1],sys.argv[2]
keys=['ct_on','ct_off','leak_rate_hz','shot_noise_rate_hz']
tot={'b':[0,0],'a':[0,0]}
for p in sorted(glob.glob(A+'/*.json')):
    n=os.path.basename(p)[:-5]
    q=B+'/'+n+'.json'
    if not os.path.exists(q): continue
    try: a=json.load(open(p)); b=json.load(open(q))
    except Exception: continue
    case=[l.strip() for l in open('leak-cases.txt') if l.strip().endswith('/'+n)][0]
    t=json.load(open(case+'/truth.json')); tv=t['values']; gen=t.get('generator','ctcal')
    line=[]
    for k in keys:
        def get(d):
            u=d['uncertainties'].get(k); v=d['params'].get(k)
            return v,(u['ci95'] if u else None)
        (bv,bc),(av,ac)=get(b),get(a)
        tr=tv.get(k,0) or 0
        def cov(v,c):
            if v is None or c is None: return None
            return (c[0] or 0)<=tr<=(c[1] if c[1] is not None else math.inf)
        cb,ca=cov(bv,bc),cov(av,ac)
        if k in ('ct_on','ct_off'):
            if cb is not None: tot['b'][0]+=1; tot['b'][1]+=cb
            if ca is not None: tot['a'][0]+=1; tot['a'][1]+=ca
        if bv!=av:
            f=lambda v: 'None' if v is None else '%.3g'%v
            line.append(f"{k} {f(tr)}: {f(bv)}{'' if cb is None else ('+' if cb else '-')} -> {f(av)}{'' if ca is None else ('+' if ca else '-')}")
    eb,ea=b.get('error_after'),a.get('error_after')
    print(n,gen,'err %.3g -> %.3g'%(eb,ea) if eb and ea else '', 'effects',[e['effect'] for e in b['effects_added']],'->',[e['effect'] for e in a['effects_added']], '; '.join(line) if line else 'same')
print('Cp/Cn covered (determinable, covered):',tot)
