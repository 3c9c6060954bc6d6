#!/bin/bash
# epppsrun.sh BIN OUT < cases : estimate eppps --json on each case, as the coverage runner runs it
bin=$1; out=$2; mkdir -p $out
while read c; do
  n=$(basename $c)
  [ -s $out/$n.json ] && continue
  timeout 600 $bin estimate eppps $c --json - --quiet --threads 1 > $out/$n.json 2>$out/$n.err
done
