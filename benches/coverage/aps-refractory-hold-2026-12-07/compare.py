# compare.py BEFORE AFTER [CASES]: per draw and polarity of `estimate aps --json` outputs
# (BEFORE/case-N.json, AFTER/case-N.json), covered / MISS / nd (not determinable) / err
# against CASES/case-N/truth.json, printed where coverage changed, the interval width moved
# by more than 2 % or the value by more than 0.005, with the hold the AFTER run fitted;
# then the counts and median relative widths.
import json,glob,os,sys,statistics
CASES=sys.argv[3] if len(sys.argv) > 3 else 'cases'
def load(p):
    try: return json.load(open(p))
    except Exception: return None
A,B=sys.argv[1],sys.argv[2]
stats={}
for p in sorted(glob.glob(B+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    b=load(p); a=load(A+'/'+n+'.json')
    if b is None and a is None: continue
    t=json.load(open(CASES+'/'+n+'/truth.json'))
    tr=None
    if b:
        d=b.get('refractory_tracking')
        if d: tr=(d['seconds'],d['standard_error'],d['bound_s'])
    for k in ('ct_on','ct_off'):
        tv=t['values'][k]
        def cov(d):
            if d is None: return 'err',None,None
            v=d.get(k); ci=d.get(k+'_ci95')
            if v is None: return 'nd',None,None
            return ('ok' if ci[0]<=tv<=ci[1] else 'MISS'), (ci[1]-ci[0])/tv, v
        ca,wa,va=cov(a); cb,wb,vb=cov(b)
        s=stats.setdefault(k,{'a':{},'b':{},'wa':[],'wb':[]})
        s['a'][ca]=s['a'].get(ca,0)+1; s['b'][cb]=s['b'].get(cb,0)+1
        if wa is not None and wb is not None: s['wa'].append(wa); s['wb'].append(wb)
        if ca!=cb or (wa and wb and abs(wb/wa-1)>0.02) or (va and vb and abs(vb-va)>0.005):
            trs='' if tr is None else f" T {tr[0]*1e3:.3f}+-{tr[1]*1e3:.3f} ms (bound {tr[2]*1e3:.3f})"
            print(f"{n} {t['generator']:9s} {k:6s} truth {tv:.3f} {ca}->{cb} value {va if va is None else round(va,3)} -> {vb if vb is None else round(vb,3)} rel.width {wa if wa is None else round(wa,3)} -> {wb if wb is None else round(wb,3)}{trs}")
for k,s in stats.items():
    print(k,'before',s['a'],'after',s['b'],'median rel width',round(statistics.median(s['wa']),3),'->',round(statistics.median(s['wb']),3), 'n',len(s['wa']))
