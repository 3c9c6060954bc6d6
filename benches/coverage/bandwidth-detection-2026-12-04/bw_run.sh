#!/bin/bash
# usage: bw_run.sh BIN OUTDIR ; fits every kept draw with a cutoff (and, with ALL=1, every kept draw)
BIN=$1; OUT=$2; mkdir -p $OUT
ls -d /work/s59/keep/cases/case-60* /work/s60/fresh7001/cases/case-70* /work/s61/cov8001/cases/case-80* > $OUT/all.txt
python3 - "$OUT" <<'PY' > $OUT/list.txt
import json,sys
for d in open(sys.argv[1]+'/all.txt').read().split():
    t=json.load(open(d+'/truth.json'))
    if t['params'].get('cutoff_hz') or __import__('os').environ.get('ALL'):
        print(d)
PY
cat $OUT/list.txt | xargs -P 2 -I{} bash -c 'c=$(basename {}); /usr/bin/time -f "%e %M" timeout 900 '$BIN' fit {} --threads 1 --json '$OUT'/$c.json > /dev/null 2> '$OUT'/$c.err'
echo done > $OUT/done
