"""Isolated-event rate at quiet pixels against the pixel's covered share (prototype)."""
import sys, numpy as np, json, os
case = sys.argv[1]; W_US = int(sys.argv[2]) if len(sys.argv) > 2 else 30000; R = int(sys.argv[3]) if len(sys.argv) > 3 else 1
tr = json.load(open(os.path.join(case, 'truth.json')))
w, h = tr['width'], tr['height']
d = np.loadtxt(os.path.join(case, 'events.txt'), comments='#', skiprows=1 if open(os.path.join(case,'events.txt')).readline().count(' ') < 3 else 0)
t = np.round(d[:, 0] * 1e6).astype(np.int64); x = d[:, 1].astype(int); y = d[:, 2].astype(int); on = d[:, 3] > 0
t0, t1 = t.min(), t.max() + 1
span = t1 - t0
p = y * w + x
cnt = np.bincount(p, minlength=w * h)
rate = cnt / (span * 1e-6)
med = np.median(rate[rate > 0])
hot = rate > max(20.0, 10 * med)
keep = ~hot[p]
t, x, y, on, p = t[keep], x[keep], y[keep], on[keep], p[keep]
order = np.argsort(p, kind='stable')
starts = np.searchsorted(p[order], np.arange(w * h + 1))
times = [t[order[starts[i]:starts[i + 1]]] for i in range(w * h)]
covshare = np.zeros(w * h); iso_on = np.zeros(w * h); iso_off = np.zeros(w * h); unc = np.zeros(w * h)
for py in range(h):
    for px in range(w):
        i = py * w + px
        if hot[i]:
            continue
        nb = [times[(yy) * w + xx] for yy in range(max(0, py - R), min(h, py + R + 1)) for xx in range(max(0, px - R), min(w, px + R + 1)) if (yy, xx) != (py, px)]
        nt = np.sort(np.concatenate(nb)) if nb else np.zeros(0, np.int64)
        if len(nt):
            lo = np.maximum(nt - W_US, t0); hi = np.minimum(nt + W_US, t1)
            # union length of sorted intervals
            cov = 0; cur_lo, cur_hi = lo[0], hi[0]
            hm = np.maximum.accumulate(hi)
            # vectorised union: new segment where lo > previous running max hi
            brk = np.ones(len(lo), bool); brk[1:] = lo[1:] > hm[:-1]
            segs = np.flatnonzero(brk)
            ends = np.append(segs[1:], len(lo)) - 1
            cov = np.sum(hm[ends] - lo[segs])
        else:
            cov = 0
        covshare[i] = cov / span
        unc[i] = (span - cov) * 1e-6
        own = order[starts[i]:starts[i + 1]]
        if len(own) and len(nt):
            tt = t[own]
            k = np.searchsorted(nt, tt)
            dl = np.where(k > 0, tt - nt[np.maximum(k - 1, 0)], 1 << 60)
            dr = np.where(k < len(nt), nt[np.minimum(k, len(nt) - 1)] - tt, 1 << 60)
            alone = (np.minimum(dl, dr) > W_US)
        else:
            alone = np.ones(len(own), bool)
        iso_on[i] = np.sum(alone & on[own]); iso_off[i] = np.sum(alone & ~on[own])
q = (covshare < 1.0) & ~hot
print(case, 'hot', hot.sum(), 'quiet', q.sum(), 'truth sn', tr['values'].get('shot_noise_rate_hz'), 'leak', tr['values'].get('leak_rate_hz'))
edges = [0, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.7, 0.9, 1.0]
for a, b in zip(edges[:-1], edges[1:]):
    s = q & (covshare >= a) & (covshare < b if b < 0.5 else covshare <= b)
    u = unc[s].sum()
    if u > 0:
        print(f"  cov {a:.2f}-{b:.2f} px {s.sum():6d} pxs {u:8.1f}  ON {iso_on[s].sum()/u:.4f}  OFF {iso_off[s].sum()/u:.4f}  (n {int(iso_on[s].sum())}/{int(iso_off[s].sum())})")
u = unc[q].sum(); print(f"  all quiet  ON {iso_on[q].sum()/u:.4f} OFF {iso_off[q].sum()/u:.4f}")
