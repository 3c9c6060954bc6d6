#!/usr/bin/env bash
# Times `ctcal fit CASE` (with frames) of one build, one line per run:
#   measure.sh BINARY LABEL OUTDIR THREADS CASE [EXTRA ARGS...]
# writes OUTDIR/LABEL-tTHREADS-NAME.json (the fit) and .time (/usr/bin/time -v), and
# prints label, threads, case, wall s, user+sys s, peak RSS MB. NAME is the case folder's
# name, or NAME=... in the environment.
set -euo pipefail
bin=$1 label=$2 out=$3 threads=$4 case=$5
shift 5
name=${NAME:-$(basename "$case")}
mkdir -p "$out"
stem="$out/$label-t$threads-$name"
/usr/bin/time -v "$bin" --quiet --threads "$threads" fit "$case" "$@" \
    --json "$stem.json" 2> "$stem.time" > /dev/null
wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, p, ":"); s = 0;
    for (i = 1; i <= n; i++) s = s * 60 + p[i]; print s}' "$stem.time")
cpu=$(awk -F': ' '/User time/ {u = $2} /System time/ {s = $2} END {print u + s}' "$stem.time")
rss=$(awk -F': ' '/Maximum resident/ {printf "%.0f", $2 / 1024}' "$stem.time")
echo "$label t$threads $name wall ${wall}s cpu ${cpu}s rss ${rss}MB"
