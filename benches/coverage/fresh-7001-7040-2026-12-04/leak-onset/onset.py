"""Isolated ON and OFF events per time block (two-sided support, 3x3, +-W), per pixel-second
of the whole sensor: does the ON excess grow with time since the recording's start?"""
import sys, numpy as np
case, W = sys.argv[1], float(sys.argv[2])
f = open(case + '/events.txt'); w, h = map(int, f.readline().split())
d = np.loadtxt(f)
t, x, y, p = d[:, 0], d[:, 1].astype(int), d[:, 2].astype(int), d[:, 3].astype(int)
t0, t1 = t.min(), t.max()
# per pixel sorted times of events at each pixel
pix = y * w + x
order = np.argsort(t, kind='stable'); t, x, y, p, pix = t[order], x[order], y[order], p[order], pix[order]
from collections import defaultdict
times = defaultdict(list)
for ti, pi in zip(t, pix): times[pi].append(ti)
times = {k: np.array(v) for k, v in times.items()}
iso = np.zeros(len(t), bool)
for i in range(len(t)):
    ok = True
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            if dx == 0 and dy == 0: continue
            q = (y[i] + dy) * w + (x[i] + dx)
            a = times.get(q)
            if a is None: continue
            j = np.searchsorted(a, t[i] - W)
            if j < len(a) and a[j] <= t[i] + W: ok = False; break
        if not ok: break
    iso[i] = ok
nb = 6
edges = np.linspace(t0, t1, nb + 1)
for b in range(nb):
    m = (t >= edges[b]) & (t < edges[b + 1]) & iso
    ps = w * h * (edges[b + 1] - edges[b])
    on, off = (m & (p == 1)).sum(), (m & (p == 0)).sum()
    print(f'{edges[b]:.2f}-{edges[b+1]:.2f} s  isolated ON {on:6d} OFF {off:6d}  excess {(on-off)/ps:.4f} Hz +- {np.sqrt(on+off)/ps:.4f}')
