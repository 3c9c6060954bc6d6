import json,sys,os,glob
out=sys.argv[1]
rows=[]
for d in open(out+'/list.txt').read().split():
    c=os.path.basename(d); t=json.load(open(d+'/truth.json'))
    tc=t['params'].get('cutoff_hz')
    if not os.path.exists(f"{out}/{c}.err"): continue
    try: f=json.load(open(f'{out}/{c}.json'))
    except Exception:
        err=open(f'{out}/{c}.err').read().strip().splitlines()
        rows.append(f"{c} {tc} | refused/failed: {err[-2][:90] if len(err)>1 else err}"); continue
    tm=open(f'{out}/{c}.err').read().split()[-2:]
    p=f['params']; u=f.get('uncertainties',{}).get('cutoff_hz',{})
    bd=f.get('bandwidth_detection')
    if 'cutoff_hz' in p and p['cutoff_hz'] is None and not u.get('ci95'):
        rows.append(f"{c} {tc} | null: {f['why'].get('cutoff_hz','')[:95]} | {tm[0]} s")
    elif 'cutoff_hz' in p:
        ci=u.get('ci95'); v=p['cutoff_hz']
        cov = tc is not None and ci and (ci[0] is None or ci[0]<=tc) and (ci[1] is None or tc<=ci[1])
        rows.append(f"{c} {tc} | cutoff {v} {ci} {'covered' if cov else 'MISSED'} | {tm[0]} s")
    elif bd:
        lim=bd['called_for_below_hz']
        if lim is None:
            s='no limit: '+bd['why'][:70]
        elif tc is None: s=f'limit {lim:.0f} (no cutoff)'
        else: s=f"limit {lim:.0f}: truth {'above (consistent)' if tc>lim else 'BELOW (limit wrong)'}"
        rows.append(f"{c} {tc} | silent; {s}; own {'-' if bd['recording_evidence'] is None else round(bd['recording_evidence'],1)}; tried {bd['tried']}; probes {len(bd['evidence'])} | {tm[0]} s")
    else:
        rows.append(f"{c} {tc} | silent, no detection (events only?) | {tm[0]} s")
print("\n".join(rows))
