"""widths.py COMPARE.txt: of the thresholds that moved, how many moved toward the truth, and the interval widths (ln hi/lo) before and after."""
import re,math,sys,statistics as st
closer=further=0; wb=[];wa=[]; rows=[]
for l in open(sys.argv[1]):
    m=re.match(r'(\S+)\s+(\S+)\s+truth ([0-9.]+): (\S+)\s+([0-9.]+) \[([0-9.]+), ([0-9.inf]+)\]\s+->\s+(\S+)\s+([0-9.]+) \[([0-9.]+), ([0-9.inf]+)\] \*$',l)
    if not m: continue
    t,b,a=float(m.group(3)),float(m.group(5)),float(m.group(9))
    if abs(math.log(a/t))<abs(math.log(b/t)): closer+=1
    else: further+=1
    bl,bh,al,ah=[float(m.group(i)) for i in (6,7,10,11)]
    if bl>0 and al>0 and bh<1e9 and ah<1e9:
        wb.append(math.log(bh/bl)); wa.append(math.log(ah/al))
print(f"moved {closer+further}: {closer} toward the truth, {further} away")
print(f"closed intervals both times: {len(wb)}; median width ln(hi/lo) {st.median(wb):.2f} -> {st.median(wa):.2f} (x{math.exp(st.median(wa))/math.exp(st.median(wb)):.2f} in hi/lo ratio terms: {math.exp(st.median(wb)):.2f} -> {math.exp(st.median(wa)):.2f})")
opened=sum(1 for l in open(sys.argv[1]) if l.rstrip().endswith('*') and '[0.000,' in l.split('->')[1] and '[0.000,' not in l.split('->')[0])
print(f"lower end opened (below the grid) by the change: {opened}")
