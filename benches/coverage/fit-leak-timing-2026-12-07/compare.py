# fitcmp.py BEFORE AFTER CASES: `ctcal fit --json` outputs per draw (BEFORE/case-N.json,
# AFTER/case-N.json) against CASES/case-N/truth.json: threshold coverage (ON, OFF), the leak
# rate's (where the truth has leak), and the effects kept; printed where any of them changed.
import json,glob,os,sys,collections
A,B,C=sys.argv[1],sys.argv[2],sys.argv[3]
def load(p):
    try: return json.load(open(p))
    except Exception: return None
def cov(d,key,truth):
    if d is None: return 'err'
    u=d.get('uncertainties',{}).get(key)
    if not u or u.get('value') is None: return 'nd'
    ci=u.get('ci95')
    if ci is None or ci[0] is None: return 'nd'
    hi=ci[1] if ci[1] is not None else float('inf')
    return 'ok' if ci[0]<=truth<=hi else 'MISS'
def effects(d):
    if d is None: return ()
    return tuple(sorted(e['effect'] for e in d.get('effects_added',[])))
tally=collections.defaultdict(collections.Counter)
for p in sorted(glob.glob(B+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    a=load(A+'/'+n+'.json'); b=load(p)
    if a is None and b is None: continue
    t=json.load(open(f'{C}/{n}/truth.json'))
    line=[]
    for key in ('ct_on','ct_off'):
        ca,cb=cov(a,key,t['values'][key]),cov(b,key,t['values'][key])
        tally[key+' before'][ca]+=1; tally[key+' after'][cb]+=1
        if ca!=cb: line.append(f"{key} {ca}->{cb}")
    lk=t['params'].get('leak_rate_hz')
    if lk is not None:
        ca,cb=cov(a,'leak_rate_hz',lk),cov(b,'leak_rate_hz',lk)
        tally['leak_rate_hz before'][ca]+=1; tally['leak_rate_hz after'][cb]+=1
        if ca!=cb: line.append(f"leak_rate_hz {ca}->{cb}")
    hasleak='leak' in t['effects']
    ea,eb=effects(a),effects(b)
    tally['leak kept, before'][('leak' in ea, hasleak)]+=1; tally['leak kept, after'][('leak' in eb, hasleak)]+=1
    if ea!=eb: line.append(f"effects {','.join(ea) or '-'} -> {','.join(eb) or '-'}")
    if line: print(n, t['generator'], ('leak' if hasleak else 'no leak'), '; '.join(line))
for k,v in tally.items(): print(k, dict(v))
