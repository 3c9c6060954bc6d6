import sys, json, numpy as np
for case in sys.argv[1:]:
    tr = json.load(open(f'{case}/truth.json'))
    W, H = tr['width'], tr['height']
    ev = np.loadtxt(f'{case}/events.txt', skiprows=1)
    t = (ev[:,0]*1e6).round().astype(np.int64); x = ev[:,1].astype(int); y = ev[:,2].astype(int); on = ev[:,3] > 0
    t0, t1 = t[0], t[-1]+1
    fit_end = t0 + round((t1-t0)*0.6)
    s = t < fit_end
    p = (y*W + x)[s]; o = on[s]
    n_on = np.bincount(p[o], minlength=W*H).astype(float); n_off = np.bincount(p[~o], minlength=W*H).astype(float)
    tot = n_on + n_off
    # crude hot exclusion
    keep = tot < np.percentile(tot[tot>0], 99.5) * 3
    # first event polarity per pixel
    order = np.arange(len(p))
    first_idx = np.full(W*H, -1); 
    uniq, fi = np.unique(p, return_index=True)
    first_on = np.zeros(W*H); first_off = np.zeros(W*H)
    first_on[uniq] = o[fi]; first_off[uniq] = ~o[fi]
    v = tr['values']; true = v['ct_on']/v['ct_off']
    A = n_off[keep].sum()/n_on[keep].sum()
    B = (n_off-first_off)[keep].sum()/(n_on-first_on)[keep].sum()
    # pixels with >= k events only
    m = keep & (tot >= 4)
    C = (n_off-first_off)[m].sum()/(n_on-first_on)[m].sum()
    D = n_off[m].sum()/n_on[m].sum()
    print(case.split('/')[-1], tr['family'][:10], 'true Cp/Cn %.3f' % true, '| OFF/ON all %.3f (ln err %+.2f)' % (A, np.log(A/true)), 'drop first %.3f (%+.2f)' % (B, np.log(B/true)), '| >=4 ev: all %.3f (%+.2f) drop first %.3f (%+.2f)' % (D, np.log(D/true), C, np.log(C/true)), 'ev/px %.2f' % (tot[keep].mean()), 'leak %.2f' % v['leak_rate_hz'])
