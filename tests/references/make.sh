#!/bin/sh
# Makes the path-traced references that tests/convergence.rs compares progressive renders with:
# photonwave's own path tracer (`--engine path`: an unbiased path tracer with next-event
# estimation, within 0.2 % of the converged reference issue 15 measured against on CornellBox-Original), 32×32, from the
# bundled scenes' cameras, 65 536 samples per pixel (the most one render takes). Run from the
# repository's root after `cargo build --release`; about 5 minutes on two cores.
set -e
pw=target/release/photonwave
$pw render scenes/cornell-box.toml --engine path --width 32 --height 32 --spp 65536 --seed 7 \
    -o tests/references/cornell-box-32.exr --quiet
$pw render scenes/cornell-spheres.toml --engine path --width 32 --height 32 --spp 65536 --seed 7 \
    -o tests/references/cornell-spheres-32.exr --quiet
