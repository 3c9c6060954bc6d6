#!/usr/bin/env bash
# Time and memory of `estimate aps` and `fit` against the recording's length (issue 19):
# one textured DAVIS240C-size scene (calib/scenes/sample_texture_davis240c.toml, 25 Hz
# frames of 5 ms, about 130 k events/s with calib/params/davis240c_like.toml) simulated
# at 1, 2, 4, ... 64 s, each command run once per build on two threads; prints a
# Markdown table of wall time, CPU time (user + system), peak resident memory and the
# thresholds (truth 0.35 / 0.45; the pixel also has 300 Hz bandwidth, refractory, leak and
# shot noise).
#
# usage: benches/scripts/length_scaling.sh BEFORE AFTER [LENGTH_S...]
#   BEFORE, AFTER: two ctcal binaries. Recordings are simulated by AFTER into
#   $WORK (default /tmp/ctcal-length) and kept there for reuse.
set -euo pipefail
cd "$(dirname "$0")/../.."
before=$1
after=$2
shift 2
lengths=("$@")
[ ${#lengths[@]} -eq 0 ] && lengths=(1 2 4 8 16 32 64)
work=${WORK:-/tmp/ctcal-length}
mkdir -p "$work"
scene=calib/scenes/sample_texture_davis240c.toml
params=calib/params/davis240c_like.toml

echo "| length | command | build | wall | CPU | peak RSS | ON | OFF | ON 95 % | OFF 95 % |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for n in "${lengths[@]}"; do
  rec=$work/len_$n
  if [ ! -d "$rec" ]; then
    sed -e "s/^duration_s = .*/duration_s = $n.0/" -e 's/^seed = .*/seed = 11/' "$scene" \
      >"$work/scene_$n.toml"
    "$after" simulate --quiet --scene "$work/scene_$n.toml" --params "$params" --out "$rec"
  fi
  for cmd in "estimate aps" "fit"; do
    for build in before after; do
      bin=$before
      [ "$build" = after ] && bin=$after
      json=$work/${cmd// /_}_${n}_$build.json
      # shellcheck disable=SC2086
      if /usr/bin/time -f "%e %U %S %M" -o "$work/time" "$bin" --quiet --threads 2 $cmd \
        "$rec" --json "$json" >/dev/null 2>"$work/stderr"; then
        read -r wall user sys rss <"$work/time"
        python3 - "$json" "$n" "$cmd" "$build" "$wall" "$user" "$sys" "$rss" <<'PY'
import json, sys
path, n, cmd, build, wall, user, sys_, rss = sys.argv[1:]
d = json.load(open(path))
fit = d.get("uncertainties", {})
def get(k):
    return fit[k]["value"] if k in fit else d[k]
def ci(k):
    c = fit[k].get("ci95") if k in fit else d.get(k + "_ci95")
    return "[%.3f, %.3f]" % tuple(c) if c and None not in c else str(c)
print("| %s s | %s | %s | %.1f s | %.1f s | %.0f MB | %.3f | %.3f | %s | %s |" % (
    n, cmd, build, float(wall), float(user) + float(sys_), int(rss) / 1024,
    get("ct_on"), get("ct_off"), ci("ct_on"), ci("ct_off")))
PY
      else
        read -r wall user sys rss < <(tail -1 "$work/time") || true
        echo "| $n s | $cmd | $build | $wall s | $(echo "$user + $sys" | bc) s | $((rss / 1024)) MB | refused: $(head -c 110 "$work/stderr" | tr '\n|' ' /')... | | | |"
      fi
    done
  done
done
