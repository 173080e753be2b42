#!/usr/bin/env bash
# The heaviest stored photon against the median one (`power_max_over_median` in --stats), for
# every bundled and hard-case scene over several seeds, with the photon counters of `numerics`:
# a spike in photon power shows as a large ratio. Renders at 8×8, 1 spp: the photon maps are the
# defaults' (200 000 global, 100 000 caustic photons); the image is not what is measured.
#
#   bash benches/photon-power.sh [SEEDS] [PHOTONWAVE]   # default: seeds 1-8, target/release
# Prints CSV: scene,seed,global,caustic,power_capped (where the binary reports it).
set -euo pipefail
cd "$(dirname "$0")/.."
seeds=${1:-8}
pw=${2:-target/release/photonwave}
[ -x "$pw" ] || cargo build --release --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "scene,seed,global,caustic,power_capped"
for scene in scenes/*.toml scenes/hard/*.toml; do
  for seed in $(seq 1 "$seeds"); do
    if ! "$pw" render "$scene" --width 8 --height 8 --spp 1 --seed "$seed" -q -o "$tmp/o.exr" \
      --stats "$tmp/s.json" 2>/dev/null; then
      echo "$scene,$seed,error,error,"
      continue
    fi
    python3 - "$scene" "$seed" "$tmp/s.json" <<'PY'
import json, sys
scene, seed, path = sys.argv[1:]
d = json.load(open(path))
g, c = d["global_map"], d["caustic_map"]
ratio = lambda m: f'{m.get("power_max_over_median", 0):.4g}' if m.get("built") else ""
print(f'{scene},{seed},{ratio(g)},{ratio(c)},{d["numerics"].get("photon_power_capped", "")}')
PY
  done
done
