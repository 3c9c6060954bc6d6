#!/bin/bash
# usage: run_fit.sh BIN TAG seeds...
BIN=$1; TAG=$2; shift 2
mkdir -p res
for s in "$@"; do
  d=/work/refr/work-$s/case-$s
  if [ ! -d $d ]; then
    /work/main/target/release/examples/coverage --cases 1 --seed $s --methods fit --timeout-s 1 --keep-cases --work /work/refr/work-$s --out /work/refr/out-$s --jobs 1 --threads 1 --ctcal /bin/false >/dev/null 2>&1
  fi
  exp=$(python3 -c "import json;c=json.load(open('$d/case.json'));r=c['recording'];print((r.get('scene') or {}).get('aps',{}).get('exposure_s',0))" 2>/dev/null)
  /usr/bin/time -f "%e s %M KB" -o res/$TAG-$s.time timeout 900 $BIN fit $d --exposure-s ${exp:-0} --json res/$TAG-$s.json --threads 1 --quiet 2> res/$TAG-$s.err
done
