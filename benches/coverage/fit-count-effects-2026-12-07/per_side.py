# per_side.py BEFORE AFTER CASES: replays the count-effect checks of AFTER's fits with the
# per-side rule (each side of ln C reaches its own furthest profile, in quadrature) in place
# of the symmetric one (the largest log change both sides), from the checks' own notes, and
# scores both against the truth beside BEFORE.
import json,glob,os,sys,re,math,collections
A,B,C=sys.argv[1],sys.argv[2],sys.argv[3]
MODE=sys.argv[4] if len(sys.argv)>4 else 'new'   # 'new': only leak/cutoff/refractory per-side; 'all': shot noise too
num=r'(-|[0-9.]+)'
pat=re.compile(r'(OFF|ON) '+num+' / '+num+' / '+num+r'(?:: (ct_o(?:n|ff)) \[([0-9.]+|open), ([0-9.]+|open)\] -> \[([0-9.]+|open), ([0-9.]+|open)\])?')
def f(x): return None if x in ('-','open') else float(x)
def cov(ci,t):
    # as compare.py: an interval open below is a bound, scored apart (not determinable)
    lo,hi=ci
    return lo is not None and lo<=t and (hi is None or t<=hi)
def scored(u,key,d,t):
    if not u or not u.get('ci95') or key in d.get('why',{}) or u['ci95'][0] is None: return 'nd'
    return 'ok' if cov(u['ci95'],t) else 'MISS'
tally=collections.defaultdict(collections.Counter); widths=[]
for p in sorted(glob.glob(B+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    try: b=json.load(open(p)); a=json.load(open(A+'/'+n+'.json'))
    except Exception: continue
    t=json.load(open(f'{C}/{n}/truth.json'))
    # per key: final interval under per-side rule
    final={}
    for key in ('ct_on','ct_off'):
        u=b['uncertainties'].get(key)
        final[key]=(u['value'],u['ci95']) if u and u.get('ci95') and key not in b.get('why',{}) else None
    notes=[x for x in b['assumptions'] if re.match(r'(noise-rate|leak-rate|cutoff|refractory) check:',x)]
    # replay in order: start from the first note's 'before' interval per key
    side={}
    for x in notes:
        kind=x.split(' check:')[0]
        if MODE=='new' and kind=='noise-rate': continue
        for m in pat.finditer(x):
            pol,lo_v,mid,hi_v,key,b0,b1,a0,a1=m.groups()
            key='ct_on' if pol=='ON' else 'ct_off'
            if m.group(5) is None: continue
            vals=[f(lo_v),f(mid),f(hi_v)]
            if vals[1] is None: continue
            side.setdefault(key,[f(b0),f(b1),0.0,0.0])
            for v in vals:
                if v is None: continue
                r=math.log(v/vals[1])
                if r>0: side[key][3]=max(side[key][3],r)
                else: side[key][2]=max(side[key][2],-r)
    for key in ('ct_on','ct_off'):
        tv=t['values'][key]
        ua=a['uncertainties'].get(key)
        ca=scored(ua,key,a,tv)
        if final[key] is None or final[key][1][0] is None: cs=cb='nd'
        else:
            v,ci=final[key]; cb='ok' if cov(ci,tv) else 'MISS'
            if key in side:
                lo,hi,dl,du=side[key]
                # the symmetric rule's widening replaced: recompute from the note's before interval
                nlo=None if lo is None else (0.0 if lo<=0 else v*math.exp(-math.hypot(math.log(v/lo),dl)))
                nhi=None if hi is None else v*math.exp(math.hypot(math.log(hi/v),du))
                # later terms? the count checks are the last threshold widening
                ci2=[nlo,nhi]
                cs='ok' if cov(ci2,tv) else 'MISS'
                if ci[0] and ci[1] and nlo and nhi: widths.append((n,key,math.log(ci[1]/ci[0]),math.log(nhi/nlo)))
            else: cs=cb
        tally[(key,'before')][ca]+=1; tally[(key,'symmetric')][cb]+=1; tally[(key,'per-side')][cs]+=1
        if len({ca,cb,cs})>1: print(n,t['generator'][:5],key,ca,cb,cs)
for k,v in sorted(tally.items()): print(k,dict(v))
r=sorted(w2/w1 for _,_,w1,w2 in widths if w1>0)
print('per-side/symmetric log width: n',len(r),'median %.3f'%r[len(r)//2] if r else '')
