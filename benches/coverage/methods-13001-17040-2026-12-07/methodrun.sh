#!/bin/bash
# methodrun.sh BIN OUT KIND CASEDIR: KIND = eppps | eppps_events | fit_events; JSON to OUT/<case>.json
bin=$1; out=$2; kind=$3; dir=$4
n=$(basename $dir)
mkdir -p $out
[ -s $out/$n.json ] && exit 0
case $kind in
  eppps) args="estimate eppps $dir";;
  eppps_events) args="estimate eppps $dir --ignore-frames";;
  fit_events) args="fit $dir --no-frames";;
esac
timeout 900 $bin $args --json $out/$n.json --quiet --threads 1 > /dev/null 2> $out/$n.err
echo "rc=$?" >> $out/$n.err
