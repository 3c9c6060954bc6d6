import json,glob,os,sys
dirs=['/work/s77/fresh15k-cases','/work/s74/cases14k','/work/s73/cases13k','/work/s78/fresh16k/work']
def casedir(n):
    for b in dirs:
        if os.path.exists(b+'/'+n): return b+'/'+n
def load(p):
    try: return json.load(open(p))
    except Exception: return None
A,B=sys.argv[1],sys.argv[2]
stats={}
for p in sorted(glob.glob(B+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    b=load(p); a=load(A+'/'+n+'.json')
    if b is None and a is None: continue
    t=json.load(open(casedir(n)+'/truth.json'))
    for k in ('ct_on','ct_off'):
        tv=t['values'][k]
        def cov(d):
            if d is None: return 'err',None
            v=d.get(k); ci=d.get(k+'_ci95')
            if v is None: return 'nd',None
            return ('ok' if ci[0]<=tv<=ci[1] else 'MISS'), (ci[1]-ci[0])/tv
        ca,wa=cov(a); cb,wb=cov(b)
        s=stats.setdefault(k,{'a':{},'b':{},'wa':[],'wb':[]})
        s['a'][ca]=s['a'].get(ca,0)+1; s['b'][cb]=s['b'].get(cb,0)+1
        if wa is not None and wb is not None: s['wa'].append(wa); s['wb'].append(wb)
        if ca!=cb or (wa and wb and abs(wb/wa-1)>0.02):
            print(f"{n} {t['generator']:9s} {k:6s} truth {tv:.3f} {ca}->{cb} rel.width {wa if wa is None else round(wa,3)} -> {wb if wb is None else round(wb,3)}")
import statistics
for k,s in stats.items():
    print(k,'before',s['a'],'after',s['b'],'median rel width',round(statistics.median(s['wa']),3),'->',round(statistics.median(s['wb']),3), 'n',len(s['wa']))
