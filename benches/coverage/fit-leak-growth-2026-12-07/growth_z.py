# growthz.py APS CASES...: per draw, the event timing's drift growth per DN in its bootstrap
# standard errors (estimate aps JSON, leak_drift), by generator and whether the truth's leak grows
# with the light (DVS-Voltmeter's k5 > 0).
import json,glob,os,sys
A=sys.argv[1]
rows=[]
for C in sys.argv[2:]:
    for d in sorted(glob.glob(C+'/case-*')):
        n=os.path.basename(d)
        try: a=json.load(open(f'{A}/{n}.json'))
        except Exception: continue
        cj=json.load(open(d+'/case.json')); t=json.load(open(d+'/truth.json'))
        def find(o,k):
            if isinstance(o,dict):
                if k in o: return o[k]
                for v in o.values():
                    r=find(v,k)
                    if r is not None: return r
            if isinstance(o,list):
                for v in o:
                    r=find(v,k)
                    if r is not None: return r
        ld=find(a,'leak_drift')
        if not ld or ld.get('per_dn_standard_error') in (None,0): continue
        g=cj['generator']; grows = g=='voltmeter' and cj['peer']['params']['k'][4]>0
        z=ld['per_dn']/ld['per_dn_standard_error']
        zm=ld['log_units_per_second_at_median_dn']/ld['standard_error']
        rows.append((z,n,g,grows,'leak' in t['effects'],zm,ld['per_dn']))
rows.sort()
for z,n,g,grows,leak,zm,pd in rows:
    print(f"{n} {g:9s} grows={int(grows)} leak={int(leak)} growth_z={z:8.1f} drift_z={zm:8.1f} per_dn={pd:.2e}")
