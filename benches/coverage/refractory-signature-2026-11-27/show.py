import json,sys,glob,os
tag=sys.argv[1]; eff=sys.argv[2] if len(sys.argv)>2 else 'refractory'
for f in sorted(glob.glob(f'res/{tag}-*.json'),key=lambda p:p):
    s=f.split('-')[-1][:-5]
    t=json.load(open(f'work-{s}/case-{s}/truth.json'))
    d=json.load(open(f))
    v=t['values']
    p=d['params']
    st=[x for x in d['steps'] if x['effect']==eff]
    line=f"case-{s} truth {eff} {v.get(eff+'_s',v.get(eff+'_rate_hz',v.get('cutoff_hz','?')))} ct {v['ct_on']:.3f}/{v['ct_off']:.3f} eff {t['effects']} | fit ct {p.get('ct_on')}/{p.get('ct_off')} added {d['effects_added']} before/after {d['error_before']:.3f}/{d['error_after']:.3f}"
    print(line)
    for x in st:
        print('   ', x['evidence'][:150], '| params', {k:round(vv,5) for k,vv in x['parameters'].items()}, '|', x.get('reason','')[:160])
