"""The event timing's drift as an upper bound on leak: per aps run with a leak in its truth,
the bound (drift / ct_on + 1.96 x 6.28 x its standard error / ct_on) against the true leak
at the frames' median DN (leak_rate_hz + leak_rate_hz_per_dn x median DN)."""
import json, sys
D = 31.4 / 5.0
rows = []
for path in sys.argv[1:]:
    for line in open(path):
        r = json.loads(line)
        out = (r.get('outcome') or {}).get('output') or {}
        d = out.get('leak_drift')
        v = r['truth']['values']
        leak = v.get('leak_rate_hz', 0.0) or 0.0
        if not d or leak <= 0:
            continue
        ct_on = out.get('ct_on')
        if not ct_on or ct_on <= 0:
            print(f"{r['case']['id']:11s} no ct_on"); continue
        per_dn = v.get('leak_rate_hz_per_dn', 0.0) or 0.0
        true = leak + per_dn * d['median_dn']
        rate = d['log_units_per_second_at_median_dn'] / ct_on
        se = d['standard_error'] / ct_on
        bound = rate + 1.96 * D * se
        rows.append((r['case']['id'], r['case']['generator'], true, rate, rate / se if se else 0, bound))
ok = given = 0
for c, g, true, rate, z, bound in rows:
    # ctcal gives no limit where the end is not above zero (TimingDrift::at_most_hz)
    if bound <= 0:
        print(f"{c:11s} {g:9s} true {true:7.3f} drift {rate:7.3f} z {z:7.1f} no limit (end {bound:.3f} below zero)")
        continue
    held = bound >= true
    ok += held
    given += 1
    print(f"{c:11s} {g:9s} true {true:7.3f} drift {rate:7.3f} z {z:7.1f} bound {bound:7.3f} ratio {rate/true:5.2f} {'ok' if held else 'MISS'}")
print(f"held {ok} of {given} limits given ({len(rows)} leak draws with a drift and an ON threshold)")
