import sys, json, numpy as np
case = sys.argv[1]
tr = json.load(open(f'{case}/truth.json'))
W, H = tr['width'], tr['height']
ev = np.loadtxt(f'{case}/events.txt', skiprows=1)
t = (ev[:,0]*1e6).round().astype(np.int64); x = ev[:,1].astype(int); y = ev[:,2].astype(int); on = ev[:,3] > 0
t0, t1 = t[0], t[-1]+1
nb = 10; edges = t0 + np.round((t1-t0)*np.arange(nb+1)/nb).astype(np.int64)
fit_end = edges[6]
p = y*W + x
def counts(sel):
    c_on = np.bincount(p[sel & on], minlength=W*H).astype(float)
    c_off = np.bincount(p[sel & ~on], minlength=W*H).astype(float)
    return c_on, c_off
sel = t < fit_end
c_on, c_off = counts(sel)
tot = (c_on + c_off).reshape(H, W)
# crude hot pixel exclusion: count far above 3x3 neighbourhood median
from numpy.lib.stride_tricks import sliding_window_view
pad = np.pad(tot, 1, mode='edge')
med = np.median(sliding_window_view(pad, (3,3)).reshape(H, W, 9), axis=2)
hot = (tot > 5*med + 10).ravel()
keep = ~hot
T = (fit_end - t0)*1e-6
def nbr(a):
    a = a.reshape(H, W); pd = np.pad(a, 1)
    s = sum(pd[1+dy:1+dy+H, 1+dx:1+dx+W] for dy in (-1,0,1) for dx in (-1,0,1) if (dy,dx)!=(0,0))
    return s.ravel()
z = nbr(c_on + c_off)
k = keep
def ols(yv, xv):
    A = np.vstack([np.ones_like(xv), xv]).T
    b, *_ = np.linalg.lstsq(A, yv, rcond=None); return b
def iv(yv, xv, zv):
    zc = zv - zv.mean(); beta = (zc*(yv-yv.mean())).sum()/(zc*(xv-xv.mean())).sum()
    return yv.mean() - beta*xv.mean(), beta
v = tr['values']
a_ols, b_ols = ols(c_on[k], c_off[k])
a_iv, b_iv = iv(c_on[k], c_off[k], z[k])
print(case.split('/')[-1], tr['family'], 'truth leak %.3f sn %.3f Cn/Cp %.3f' % (v['leak_rate_hz'], v['shot_noise_rate_hz'], v['ct_off']/v['ct_on']), 'T %.2f s' % T,
      '| OLS leak %.3f slope %.3f | IV leak %.3f slope %.3f' % (a_ols/T, b_ols, a_iv/T, b_iv), 'mean on %.2f off %.2f' % (c_on[k].mean()/T, c_off[k].mean()/T))
# warm-up: per block
fired_before = np.zeros(W*H, bool)
rows = []
for b in range(6):
    s = (t >= edges[b]) & (t < edges[b+1])
    con, coff = counts(s)
    Tb = (edges[b+1]-edges[b])*1e-6
    zb = nbr(con+coff)
    newly = (con+coff > 0) & ~fired_before
    a, beta = iv(con[k], coff[k], zb[k])
    rows.append((a/Tb, newly[k].mean()/Tb, beta))
    fired_before |= (con+coff > 0)
rows = np.array(rows)
# intercept_rate = lam - m' * newly_rate
A = np.vstack([np.ones(6), rows[:,1]]).T
sol, *_ = np.linalg.lstsq(A, rows[:,0], rcond=None)
print('   per block IV intercept/s', np.round(rows[:,0],3), 'newly/s', np.round(rows[:,1],3), 'slopes', np.round(rows[:,2],2), '=> leak %.3f m %.3f' % (sol[0], sol[1]))
