#!/bin/bash
# fitrun.sh BIN OUT < cases : fit --json on each case (with the case's exposure as the coverage runner gives it)
bin=$1; out=$2; mkdir -p $out
while read c; do
  n=$(basename $c)
  [ -f $out/$n.json ] && continue
  e=$(python3 -c "import json;d=json.load(open('$c/case.json'));a=d['recording'].get('scene',{}).get('aps');print(a['exposure_s'] if a else '')")
  extra=""; [ -n "$e" ] && extra="--exposure-s $e"
  timeout 600 $bin fit $c $extra --json - --quiet --threads 1 > $out/$n.json 2>$out/$n.err
done
