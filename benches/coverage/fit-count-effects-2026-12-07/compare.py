# compare.py BEFORE AFTER CASES: threshold coverage before/after, the log-width ratio of each
# threshold interval, which count-effect check, look-alike term or unseen-effect check (an assumption
# starting with its name) fired, and the simulations' count before/after.
import json,glob,os,sys,collections,math
A,B,C=sys.argv[1],sys.argv[2],sys.argv[3]
def load(p):
    try: return json.load(open(p))
    except Exception: return None
def cov(d,key,truth):
    if d is None: return 'err',None
    u=d.get('uncertainties',{}).get(key)
    if not u or u.get('value') is None or key in d.get('why',{}): return 'nd',None
    ci=u.get('ci95')
    if ci is None or ci[0] is None: return 'nd',None
    hi=ci[1] if ci[1] is not None else float('inf')
    w=math.log(hi/ci[0]) if ci[0]>0 and math.isfinite(hi) else float('inf')
    return ('ok' if ci[0]<=truth<=hi else 'MISS'),w
tally=collections.defaultdict(collections.Counter)
ratios=[];sims=[]
for p in sorted(glob.glob(B+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    a=load(A+'/'+n+'.json'); b=load(p)
    if a is None or b is None: continue
    t=json.load(open(f'{C}/{n}/truth.json'))
    split='held' if n.startswith('case-17') else 'study'
    line=[]
    fired=[k for k,s in (('leak','leak-rate check'),('cutoff','cutoff check'),('refr','refractory check'),('noise','noise-rate check'),('alike','the thresholds of the models the data do not separate'),('u-leak','unseen leak-rate check'),('u-noise','unseen noise-rate check'),('u-cut','unseen cutoff check')) if any(x.startswith(s) for x in b.get('assumptions',[]))]
    for key in ('ct_on','ct_off'):
        (ca,wa),(cb,wb)=cov(a,key,t['values'][key]),cov(b,key,t['values'][key])
        tally[(split,key,'before')][ca]+=1; tally[(split,key,'after')][cb]+=1
        if wa and wb and math.isfinite(wa) and math.isfinite(wb) and wb>wa*1.0001: ratios.append(wb/wa); line.append(f"{key} width x{wb/wa:.2f}")
        if ca!=cb: line.append(f"{key} {ca}->{cb}")
    sims.append((a.get('simulations',0),b.get('simulations',0)))
    if line or fired: print(n, t['generator'][:5], t['family'][:12], fired, '; '.join(line))
for k,v in sorted(tally.items()): print(k, dict(v))
ratios.sort()
if ratios: print('widened',len(ratios),'median x%.2f'%ratios[len(ratios)//2],'max x%.2f'%ratios[-1])
sa=sum(x for x,_ in sims); sb=sum(y for _,y in sims); print('simulations',sa,'->',sb, 'x%.3f'%(sb/max(sa,1)))
