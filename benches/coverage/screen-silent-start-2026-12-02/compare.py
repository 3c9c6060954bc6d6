"""Compares one method's thresholds of two coverage runs draw by draw.

Usage: python3 compare.py BEFORE/results.compact.jsonl AFTER/results.compact.jsonl METHOD

Prints, per draw run in both, the generator, the seconds, and each polarity's value with
its interval before (a) and after (b), "!" where the interval misses the truth (t), then
covered / determinable before and after.
"""
import json,sys
def load(p, method):
    d={}
    for l in open(p):
        r=json.loads(l)
        if r['method']!=method: continue
        d[r['case']['id']]=r
    return d
method=sys.argv[3]
a=load(sys.argv[1],method); b=load(sys.argv[2],method)
tot={}
for cid in sorted(b, key=lambda c:int(c.split('-')[1])):
    if cid not in a: continue
    out=[cid, b[cid]['truth'].get('generator','ctcal'), '%.0f->%.0fs'%(a[cid]['seconds'], b[cid]['seconds'])]
    for k in ('ct_on','ct_off'):
        t=b[cid]['truth']['values'][k]
        for tag,r in (('a',a[cid]),('b',b[cid])):
            v=r['reported'].get(k,{})
            if v.get('status')=='interval':
                lo,hi=v.get('lo'),v.get('hi'); ok=(lo is None or lo<=t) and (hi is None or t<=hi)
                tot.setdefault((k,tag),[0,0]); tot[(k,tag)][0]+=ok; tot[(k,tag)][1]+=1
                out.append('%s%s %.3f [%s, %s]%s'%(k[3:],tag, v['value'], '%.3f'%lo if lo is not None else '-', '%.3f'%hi if hi is not None else '-', '' if ok else '!'))
            else: out.append('%s%s %s'%(k[3:],tag,v.get('status')))
        out.append('t %.3f'%t)
    print(' | '.join(out))
for k in ('ct_on','ct_off'):
    print(k, 'before %s/%s'%tuple(tot.get((k,'a'),[0,0])), 'after %s/%s'%tuple(tot.get((k,'b'),[0,0])))
