#!/bin/bash
c=$1; n=$(basename $(dirname $c)).$(basename $c)
out=/work/s70/resp/$n.txt
[ -e $out ] && exit 0
( CTCAL_DEBUG_RESPONSE=exit timeout 120 /work/s70/ctcal-dbg --threads 1 estimate aps $c --quiet --json /dev/null 2>&1 >/dev/null | grep -m1 RESPONSE ) > $out.tmp; mv $out.tmp $out
