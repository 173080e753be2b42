#!/usr/bin/env bash
# Equal-time error on McGuire's five public Cornell boxes (../shared/scenes/cornellbox-*): each
# box rendered with `--time` by each binary given, in turn (binary A, binary B, A, B, … so that
# a drifting machine affects both alike), against a path-traced reference of the box, rendered
# once and kept in benches/five-boxes/ (not committed: *.exr is ignored).
#
#   bash benches/five-boxes.sh BIN_A [BIN_B …]         # defaults below
#   TIME=20s ROUNDS=2 SIZE=128 REF_SPP=4096 bash benches/five-boxes.sh target/release/photonwave
#
# Prints CSV: box,binary,round,passes,mean_ratio,rel_mse (the beauty image's).
# Cameras: Original and Mirror from the front (eye 0,1,3.4, target 0,1,0, fov 40); the squashed
# boxes (Sphere, Water, Glossy) from eye 0,0.8,3.0 toward 0,0.8,0, fov 38.
set -euo pipefail
cd "$(dirname "$0")/.."
shared=../shared/scenes
[ -d "$shared" ] || { echo "needs ../shared/scenes (the public Cornell boxes)" >&2; exit 1; }
time_budget=${TIME:-20s}
rounds=${ROUNDS:-2}
size=${SIZE:-128}
ref_spp=${REF_SPP:-4096}
[ $# -gt 0 ] || set -- target/release/photonwave
out=benches/five-boxes
mkdir -p "$out"
ref_bin=$1
camera() {
  case $1 in
    original|mirror) echo "--eye 0,1,3.4 --target 0,1,0 --fov 40" ;;
    *) echo "--eye 0,0.8,3.0 --target 0,0.8,0 --fov 38" ;;
  esac
}
echo "box,binary,round,passes,mean_ratio,rel_mse"
for box in original mirror sphere water glossy; do
  obj=$(ls "$shared/cornellbox-$box"/*.obj)
  ref="$out/$box-ref-$size-$ref_spp.exr"
  if [ ! -f "$ref" ]; then
    # Another seed than the renders' (1); 256 bounces, so that light trapped in glass is not cut.
    # shellcheck disable=SC2046
    "$ref_bin" render "$obj" $(camera "$box") --width "$size" --height "$size" --engine path \
      --spp "$ref_spp" --max-depth 256 --seed 9001 -o "$ref" -q
  fi
  for round in $(seq 1 "$rounds"); do
    for bin in "$@"; do
      img=$(mktemp --suffix .exr)
      stats=$(mktemp --suffix .json)
      # shellcheck disable=SC2046
      "$bin" render "$obj" $(camera "$box") --width "$size" --height "$size" --time "$time_budget" \
        -o "$img" --stats "$stats" -q
      "$ref_bin" compare "$img" "$ref" --json | python3 -c "
import json, sys
c = json.load(sys.stdin); s = json.load(open('$stats'))
b = next(l for l in c['layers'] if l['layer'] == 'beauty')
print(f\"$box,$bin,$round,{s['progressive']['passes']},{b['mean_ratio']:.5f},{b['rel_mse']:.6f}\")"
      rm -f "$img" "$stats"
    done
  done
done
