# checks.py AFTER: how many fits ran each count-effect check and the look-alike term, how
# many thresholds each check made not determined, and in how many fits the look-alike term
# widened an interval.
import json,glob,os,re,sys,collections
c=collections.Counter(); nd=collections.Counter()
for p in sorted(glob.glob(sys.argv[1]+'/case-*.json')):
    b=json.load(open(p))
    for a in b['assumptions']:
        m=re.match(r'(noise-rate|leak-rate|cutoff|refractory) check:',a)
        if m:
            c[m.group(1)]+=1
            nd[m.group(1)]+=a.count(': not determined')
        if a.startswith('the thresholds of the models the data do not separate'):
            c['look-alike']+=1
            if 'reach them' in a: nd['look-alike widened']+=1
print('checks run (fits):',dict(c)); print('thresholds made not determined / look-alike fits widened:',dict(nd))
