#!/usr/bin/env bash
# Wall time of every estimator and of the fit on every shared case (the 30 s and 2 min
# budgets of the estimate and fit issues), on all cores.
#
# usage: benches/scripts/estimate_fit_times.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --quiet --bin ctcal
data=../shared/data
run() {
  local what=$1; shift
  /usr/bin/time -f "%e" -o /tmp/ctcal_time target/release/ctcal --quiet "$@" --json /dev/null \
    >/dev/null 2>&1 && printf '%-52s %6.1f s\n' "$what" "$(cat /tmp/ctcal_time)" \
    || printf '%-52s failed\n' "$what"
}
for case in "$data"/oracle/*/; do
  name=$(basename "$case")
  if [ -f "$case/images.txt" ]; then
    run "$name: estimate aps" estimate aps "$case"
    run "$name: estimate eppps" estimate eppps "$case"
    run "$name: fit" fit "$case"
  fi
  if [ -f "$case/stimulus.txt" ]; then
    run "$name: estimate screen" estimate screen "$case"
  fi
done
for rec in ijrr_slider_depth_50k davis346_faery.aedat4; do
  run "$rec: estimate aps" estimate aps "$data/real/$rec"
  run "$rec: estimate eppps" estimate eppps "$data/real/$rec"
  run "$rec: fit" fit "$data/real/$rec"
done
for rec in evk4_faery_evt3.raw dvxplorer_tonic.aedat4; do
  run "$rec: estimate eppps" estimate eppps "$data/real/$rec"
done
