#!/usr/bin/env bash
# Share of `ctcal simulate --scene` spent rendering the scene, per scene of calib/scenes, on
# THREADS threads (default one; on more, it is a share of all threads' CPU samples, not of
# the wall time): `perf record` with DWARF call graphs, and the share of samples under a
# scene's renderer (`TextureScene::render`, `CheckerboardScene::render`,
# `MultiObjectWorld::render`: the source frames and the APS frames, libm calls included; a
# symbol listed twice counts once, at its larger share). Also the median wall and user
# time of RUNS plain runs (no perf).
#
# usage: benches/scripts/render_share.sh [BINARY] [PARAMS]
#   BINARY default target/release/ctcal, PARAMS default calib/params/ideal.toml;
#   RUNS (default 5) timed runs per scene; SCENES (default calib/scenes/*.toml); THREADS
#   (default 1) the runs' --threads.
set -uo pipefail
cd "$(dirname "$0")/../.."
binary=${1:-target/release/ctcal}
params=${2:-calib/params/ideal.toml}
runs=${RUNS:-5}
threads=${THREADS:-1}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
printf '%-28s %8s %8s %8s\n' scene wall_s user_s render
for scene in ${SCENES:-calib/scenes/*.toml}; do
  run() { "$binary" --threads "$threads" simulate --quiet --params "$params" --scene "$scene" --out "$work/out" >/dev/null; }
  for _ in $(seq "$runs"); do
    rm -rf "$work/out"
    /usr/bin/time -f '%e %U' -a -o "$work/times" bash -c "$(declare -f run); binary=$binary params=$params scene=$scene work=$work threads=$threads; run"
  done
  wall=$(awk '{ print $1 }' "$work/times" | median)
  user=$(awk '{ print $2 }' "$work/times" | median)
  rm -f "$work/times"
  rm -rf "$work/out"
  perf record -q -F 1999 --call-graph dwarf,16384 -o "$work/perf.data" \
    "$binary" --threads "$threads" simulate --quiet --params "$params" --scene "$scene" --out "$work/out" >/dev/null 2>&1
  share=$(perf report -i "$work/perf.data" --children --sort symbol --stdio -g none 2>/dev/null |
    grep -E '(TextureScene|CheckerboardScene|MultiObjectWorld)::render *(-|$)' |
    awk '{ gsub("%", "", $1); if ($1 > best[$4]) best[$4] = $1 }
      END { for (f in best) s += best[f]; printf "%.1f %%", s }')
  printf '%-28s %8s %8s %8s\n' "$(basename "$scene" .toml)" "$wall" "$user" "$share"
done
