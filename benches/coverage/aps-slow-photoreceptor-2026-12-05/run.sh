#!/bin/bash
# `estimate aps` of one kept draw with BIN, its JSON to OUTDIR/SET.CASE.json, its wall time
# appended to OUTDIR/times.txt (one thread). usage: run.sh BIN OUTDIR CASE
# e.g. xargs -P2 -n1 ./run.sh BIN OUT < /work/s69/aps-survey/list.txt
bin=$1; outdir=$2; c=$3; set=$(basename $(dirname $c)); n=$(basename $c)
out=$outdir/$set.$n.json
[ -e $out ] && exit 0
s=$(date +%s.%N)
$bin --threads 1 estimate aps $c --json $out --quiet >/dev/null 2>$outdir/$set.$n.err || true
echo "$set.$n $(echo "$(date +%s.%N) - $s" | bc)" >> $outdir/times.txt
