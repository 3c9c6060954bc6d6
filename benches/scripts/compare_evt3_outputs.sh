#!/usr/bin/env bash
# Identity check for EVT3 decoder work: stdout, stderr, exit code and written files of a
# reference build (BEFORE) and of this tree's build (AFTER) must be identical on every
# INPUT for `info` (one and two threads, --json, --sensor), `stats` (one and two threads,
# --sort, --sensor) and `convert` (to HDF5, and to EVT3: a round trip). Meant for the files of
# `benches/scripts/evt3_hostile_files.py` (every error message is compared), a real
# recording and the 10 M-event speed input.
#
# usage: benches/scripts/compare_evt3_outputs.sh BEFORE AFTER INPUT...
# Prints one line per comparison and exits non-zero if any output differs.
# (the runs write into a scratch folder, so every path is made absolute first)
before=$(realpath "$1"); after=$(realpath "$2"); shift 2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
n=0; bad=0
run() { # tag bin args...
  local tag=$1 bin=$2; shift 2
  rm -rf "$work/out"; mkdir -p "$work/out"
  (cd "$work/out" && "$bin" "$@" >"$work/$tag.stdout" 2>"$work/$tag.stderr"; echo $? >"$work/$tag.rc")
  for f in "$work"/out/*; do [ -e "$f" ] && cat "$f"; done >"$work/$tag.files" 2>/dev/null
}
for input in "$@"; do
  input=$(realpath "$input")
  for variant in "--threads 1 info" "--threads 2 info" "--threads 1 info --json j.json" \
      "--threads 1 stats --quiet --json j.json" "--threads 2 stats --quiet --json j.json" \
      "--threads 2 stats --sort --quiet --json j.json" "--threads 1 stats --quiet --json j.json --sensor 100x100" \
      "--threads 2 stats --sort --quiet --json j.json --sensor 4096x4096" "--threads 1 info --sensor 4096x4096" "--threads 1 convert --quiet --out conv.h5" "--threads 1 convert --quiet --out conv.raw"; do
    # shellcheck disable=SC2086
    run b "$before" $variant "$input"
    # shellcheck disable=SC2086
    run a "$after" $variant "$input"
    n=$((n+1))
    if cmp -s "$work/b.stdout" "$work/a.stdout" && cmp -s "$work/b.stderr" "$work/a.stderr" && cmp -s "$work/b.rc" "$work/a.rc" && cmp -s "$work/b.files" "$work/a.files"; then
      echo "same (exit $(cat "$work/a.rc"), $(wc -c <"$work/a.stdout")+$(wc -c <"$work/a.files") bytes): $(basename "$input") $variant"
    else
      echo "DIFFERS: $(basename "$input") $variant"; bad=$((bad+1))
      diff "$work/b.stderr" "$work/a.stderr" | head -5
    fi
  done
done
echo "$n comparisons, $bad differ"
[ "$bad" = 0 ]
