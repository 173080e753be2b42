#!/bin/sh
# Makes the path-traced references that tests/convergence.rs compares progressive renders with:
# photonwave's own path tracer (`--engine path`: an unbiased path tracer with next-event
# estimation, within 0.2 % of the converged reference issue 15 measured against on
# CornellBox-Original), 32×32, from the bundled scenes' cameras, 65 536 samples per pixel (the
# most one render takes) per file; the test averages a scene's files. Run from the repository's
# root after `cargo build --release`; about 12 minutes on two cores, and about 10 more for the interior.
set -e
pw=target/release/photonwave
$pw render scenes/cornell-box.toml --engine path --width 32 --height 32 --spp 65536 --seed 7 \
    -o tests/references/cornell-box-32-7.exr --quiet
# The glass-sphere box's caustics need more samples: four renders, averaged by the test.
for seed in 7 8 9 10; do
    $pw render scenes/cornell-spheres.toml --engine path --width 32 --height 32 --spp 65536 \
        --seed $seed -o tests/references/cornell-spheres-32-$seed.exr --quiet
done
# The bundled interior (scenes/interior.xml): light reflected by its near-mirror floor from small
# lights onto the walls is found by a path tracer only when a bounce off the floor hits a light,
# so it too gets four renders.
for seed in 7 8 9 10; do
    $pw render scenes/interior.xml --engine path --width 32 --height 32 --spp 65536 \
        --seed $seed -o tests/references/interior-32-$seed.exr --quiet
done
