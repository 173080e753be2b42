#!/usr/bin/env bash
# Error against time for every quality knob on the bundled glass-sphere Cornell box: renders a
# reference with `--preset reference` (once; ~15 min on 2 cores), then one `photonwave sweep` per
# knob, each starting from the default settings. Writes benches/error-vs-time/KNOB/{sweep.csv,
# *.svg, *.png}; docs/src/compare-sweep.md and BENCHMARKS.md quote these files.
#
#   bash benches/error-vs-time.sh            # everything
#   SIZE=64 bash benches/error-vs-time.sh    # a quicker, smaller run
set -euo pipefail
cd "$(dirname "$0")/.."
size=${SIZE:-128}
out=benches/error-vs-time
scene=scenes/cornell-spheres.toml
cargo build --release --quiet
pw=target/release/photonwave
mkdir -p "$out"
ref="$out/reference-${size}.exr"   # not committed (*.exr is ignored): re-made when missing
if [ ! -f "$ref" ]; then
  # Another seed than the sweeps' (1), so that no render shares random numbers with it.
  "$pw" render "$scene" --preset reference --width "$size" --height "$size" --seed 9001 \
    -o "$ref" --stats "$out/reference-${size}.json" -q
fi
sweep() {
  local name=$1 layer=$2
  shift 2
  "$pw" sweep "$scene" --reference "$ref" --layer "$layer" -o "$out/$name" -q "$@"
}
# Progressive passes (16 passes ≈ one default render's work), with and without per-pixel radii.
sweep passes caustic --knob passes=1,2,4,8,16,32,64,128 --knob per_pixel_radii=true,false
# The same two radius schemes at equal time.
sweep equal-time caustic --knob per_pixel_radii=true,false --time 2s,4s,8s,16s,32s
# One-pass knobs, each from the defaults, plotted on the layer they act on.
sweep photons indirect --knob photons=50000,100000,200000,400000,800000
sweep caustic_photons caustic --knob caustic_photons=25000,50000,100000,200000,400000,800000
sweep k indirect --knob k=16,32,64,128,256
sweep caustic_k caustic --knob caustic_k=12,24,48,96,192
sweep kernel caustic --knob kernel=box,cone,epanechnikov
sweep gather_rays indirect --knob gather_rays=4,8,16,32,64
sweep final_gather indirect --knob final_gather=true,false --knob precompute_irradiance=true,false
sweep spp beauty --knob spp=4,16,64
sweep max_depth beauty --knob max_depth=1,2,3,5,10
