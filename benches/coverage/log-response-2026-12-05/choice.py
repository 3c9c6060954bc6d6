import glob,re,json,os
rows=[]
for f in sorted(glob.glob('*.txt')):
    s=open(f).read().strip()
    if not s: continue
    m=re.search(r'ratio ([\d.]+) ci ([\d.inf]+) ([\d.inf]+) replace (\w+) clear (\w+) own (.*?) pure (.*?) b_own ([-\d.]+) b_pure ([-\d.]+)',s)
    if not m: print('??',f,s[:100]); continue
    st,case=f[:-4].split('.',1)
    d={'cases':'/work/s65/cases','fresh10k-cases':'/work/s66/fresh10k-cases','measured-cases':'/work/s67/measured-cases','peer11k-cases':'/work/s68/peer11k-cases','fresh11k-cases':'/work/s68/fresh11k-cases'}.get(st)
    tr=json.load(open(f'{d}/{case}/truth.json'))['values'] if d and os.path.exists(f'{d}/{case}/truth.json') else {}
    Some=lambda x:x; None_=None; own=eval(m.group(6)); pure=eval(m.group(7))
    rows.append((f,float(m.group(1)),m.group(2),m.group(3),m.group(4),m.group(5),own,pure,tr.get('ct_on'),tr.get('ct_off')))
n=len(rows); amb=[r for r in rows if r[5]=='false']
print('cases',n,'replace',sum(r[4]=='true' for r in rows),'ambiguous',len(amb))
for r in amb:
    own,pure=r[6],r[7]
    print(r[0][:28].ljust(28),'ratio %.3f ci %s %s repl %s'%(r[1],r[2][:5],r[3][:5],r[4]),'own',tuple(round(x,3) for x in own) if own else None,'pure',tuple(round(x,3) for x in pure) if pure else None,'truth',r[8],r[9])
print('--- clear choices where the two differ by > 15 %')
import math
good=bad=0
for r in rows:
    if r[5]!="true" or not r[6] or not r[7] or r[8] is None or min(r[6]+r[7])<=0: continue
    own,pure=r[6],r[7]
    d=max(abs(math.log(own[0]/pure[0])),abs(math.log(own[1]/pure[1])))
    if d<math.log(1.15): continue
    ch = pure if r[4]=='true' else own
    ot = own if r[4]=='true' else pure
    err=lambda x: abs(math.log(x[0]/r[8]))+abs(math.log(x[1]/r[9]))
    ok = err(ch)<=err(ot); good+=ok; bad+= not ok
    print(r[0][:28].ljust(28),'ratio %.3f ci %s %s repl %s'%(r[1],r[2][:5],r[3][:5],r[4]),'own',tuple(round(x,3) for x in own),'pure',tuple(round(x,3) for x in pure),'truth',r[8],r[9],'OK' if ok else 'WRONG')
print('chosen closer',good,'other closer',bad)
