"""The share of the drift's rate, in quadrature with its dispersion-scaled error, that a
limit needs to lie above the true leak: per draw the least share (None: no share helps, the
drift not above zero), then the smallest share covering 95 % of the study draws, and the
record of the limit with it on every set."""
import json, math, sys
D, Z = 31.4 / 5.0, 1.959964
# the share of the drift's rate added in quadrature (crates/ctcal-core/src/fit/effects/leak.rs)
SHARE = 0.65

def rows(path):
    out = []
    for line in open(path):
        r = json.loads(line)
        o = (r.get('outcome') or {}).get('output') or {}
        d, v = o.get('leak_drift'), r['truth']['values']
        leak = v.get('leak_rate_hz', 0.0) or 0.0
        if not d or leak <= 0 or not o.get('ct_on') or o['ct_on'] <= 0:
            continue
        true = leak + (v.get('leak_rate_hz_per_dn', 0.0) or 0.0) * d['median_dn']
        rate = d['log_units_per_second_at_median_dn'] / o['ct_on']
        se = d['standard_error'] / o['ct_on']
        out.append((r['case']['id'], r['case']['generator'], true, rate, se))
    return out

def end(rate, se, share):
    return rate + Z * math.hypot(D * se, share * max(rate, 0.0))

def least_share(true, rate, se):
    need = (true - rate) / Z
    if need <= D * se:
        return 0.0
    if rate <= 0:
        return None
    return math.sqrt(need ** 2 - (D * se) ** 2) / rate

def record(rs, share):
    given = [(c, g, t, r, s) for c, g, t, r, s in rs if se_ok(s) and end(r, s, share) > 0]
    held = [x for x in given if end(x[3], x[4], share) >= x[2]]
    return len(held), len(given), [x[0] for x in given if x not in held]

def se_ok(se):
    return se > 0 and math.isfinite(se)

if __name__ == '__main__':
    study = rows(sys.argv[1])
    held_out = [x for p in sys.argv[2:] for x in rows(p)]
    print(f"drift / ct_on from each draw's estimate aps; truth at the frames' median DN")
    needs = sorted(((least_share(t, r, s), c) for c, _, t, r, s in study), key=lambda x: math.inf if x[0] is None else x[0])
    print(f"study draws {len(study)}; least share per draw, sorted (None: no share helps):")
    print("  " + ", ".join(f"{c} {'None' if x is None else round(x, 3)}" for x, c in needs if x != 0.0) + f"; {sum(1 for x, _ in needs if x == 0.0)} draws need none")
    share = SHARE
    print(f"share used (leak.rs DRIFT_READS_LOW): {share}")
    for name, rs in (('study', study), ('held out', held_out)):
        for s in (0.0, share):
            h, g, miss = record(rs, s)
            print(f"{name:8s} share {s:.3f}: held {h} of {g} ({100*h/max(g,1):.1f} %), misses {miss}")
    for c, g, t, r, s in study + held_out:
        print(f"{c:11s} {g:9s} true {t:7.3f} drift {r:7.3f} z {r/s:7.1f} end {end(r, s, 0):7.3f} -> {end(r, s, share):7.3f}")
