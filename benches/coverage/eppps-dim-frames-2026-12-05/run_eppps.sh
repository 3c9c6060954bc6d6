#!/bin/bash
# usage: diag.sh OUTDIR BIN case-dirs...
out=$1; bin=$2; shift 2
mkdir -p $out
printf '%s\n' "$@" | xargs -P 2 -I{} bash -c 'c={}; n=$(basename $c); timeout 600 '"$bin"' estimate eppps $c --json '"$out"'/$n.json --quiet --threads 1 >/dev/null 2>'"$out"'/$n.err'
