# table.py OUT CASE_PARENT...: per draw and polarity of `estimate aps --json` outputs in OUT
# (OUT/case-N.json), the truth (CASE_PARENT/case-N/truth.json), covered / MISS / nd, the
# peak z of estimators[0].details.{on,off}.peak, and what withheld or widened it: PEAK (no
# threshold peak above the noise), SLOWOFF (an offset beside a slow photoreceptor not taken).
import json,glob,os,sys
dirs=sys.argv[2:]
def casedir(n):
    for b in dirs:
        if os.path.exists(b+'/'+n): return b+'/'+n
rows=[]
for p in sorted(glob.glob(sys.argv[1]+'/case-*.json')):
    n=os.path.basename(p)[:-5]
    try: d=json.load(open(p))
    except Exception: continue
    t=json.load(open(casedir(n)+'/truth.json'))['values']
    src=(d.get('frame_offset_dn',{}).get('estimate') or {}).get('source','-')
    for k,pk in (('ct_on','on'),('ct_off','off')):
        peak=(d['estimators'][0]['details'].get(pk) or {}).get('peak') or {}
        why=d.get('why',{}).get(k,'')
        v=d.get(k); ci=d.get(k+'_ci95')
        cov='nd' if v is None else ('ok' if ci[0]<=t[k]<=ci[1] else 'MISS')
        flag=('PEAK' if 'no threshold peak' in why else '')+(' SLOWOFF' if src.startswith('not determined: a photoreceptor slower') else '')
        print(f"{n} {k:6s} truth {t[k]:.3f} {cov:4s} z {peak.get('z',float('nan')):7.1f} {flag}")
