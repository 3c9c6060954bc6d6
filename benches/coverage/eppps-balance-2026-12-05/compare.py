import json,sys
def load(p):
    d={}
    for l in open(p):
        r=json.loads(l); d[(r['case']['seed'],r['method'])]=r
    return d
a=load(sys.argv[1]); b=load(sys.argv[2])
import collections
tab=collections.defaultdict(lambda:[0,0,0,0])
for key in sorted(b):
    if key not in a: continue
    ra,rb=a[key],b[key]
    t=rb['truth']['values'] if rb.get('truth') else None
    if not t: continue
    for k in ('ct_on','ct_off'):
        def st(r):
            x=r.get('reported',{}).get(k)
            if not x or x.get('status')!='interval': return None
            lo=x['lo'] or 0; hi=x['hi'] or 1e12
            return (lo<=t[k]<=hi, x['value'], lo, hi)
        sa,sb=st(ra),st(rb)
        m=key[1]
        if sa: tab[(m,k)][0]+=1; tab[(m,k)][1]+=sa[0]
        if sb: tab[(m,k)][2]+=1; tab[(m,k)][3]+=sb[0]
        if sa and sb and (sa[2]!=sb[2] or sa[3]!=sb[3]):
            wa=sa[3]/max(sa[2],1e-9); wb=sb[3]/max(sb[2],1e-9)
            print(key, k, 'truth %.3f'%t[k], 'before %.3f [%.3f,%.3f] %s'%(sa[1],sa[2],sa[3],'Y' if sa[0] else 'MISS'), 'after [%.3f,%.3f] %s'%(sb[2],sb[3],'Y' if sb[0] else 'MISS'), 'width x%.2f'%(wb/wa))
for k,v in sorted(tab.items()):
    print(k, 'before %d/%d'%(v[1],v[0]), 'after %d/%d'%(v[3],v[2]))
