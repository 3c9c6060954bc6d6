import json,os
D={'cases':'/work/s65/cases','fresh10k-cases':'/work/s66/fresh10k-cases','measured-cases':'/work/s67/measured-cases','peer11k-cases':'/work/s68/peer11k-cases','fresh11k-cases':'/work/s68/fresh11k-cases'}
import sys
newdir=sys.argv[1] if len(sys.argv)>1 else '/work/s70/amb'
cov=[0,0,0,0]
for n in open('/work/s70/amb/list').read().split():
    st,case=n.split('.',1)
    tr=json.load(open(f'{D[st]}/{case}/truth.json'))['values']
    old=f'/work/s69/aps-survey/out/{n}.json'; new=f'{newdir}/{n}.json'
    def get(p):
        if not os.path.exists(p): return None
        d=json.load(open(p)); return d
    o,w=get(old),get(new)
    line=n.ljust(28)
    for k in ['ct_on','ct_off']:
        t=tr[k]
        def f(d):
            if not d or d.get(k) is None: return 'nd'.ljust(24)
            lo,hi=d[k+'_ci95']; c='Y' if lo is not None and hi is not None and lo<=t<=hi else 'N'
            return f'{d[k]:.3f}[{lo:.3f},{hi:.3f}]{c}'.ljust(24)
        fo,fw=f(o),f(w)
        cov[0]+=fo.strip().endswith('Y'); cov[1]+=fw.strip().endswith('Y'); cov[2]+=not fo.startswith('nd'); cov[3]+=not fw.startswith('nd')
        line+=f' {k} t={t:.3f} old {fo} new {fw}'
    print(line)
print('covered old %d/%d new %d/%d'%(cov[0],cov[2],cov[1],cov[3]))
