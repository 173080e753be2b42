//! photonwave: a photon-mapping renderer (Jensen 1996).
//!
//! Reflected radiance splits into four terms, each computed the way that suits it: direct light
//! (light sampling with shadow rays), specular and glossy reflection (ray tracing), caustics
//! (caustic photon map) and soft indirect light (final gather over the global photon map).
//!
//! # Module map, in layer order
//! Each module imports only from the modules above it (`python3 ../shared/tools/layers.py src`
//! prints any cycle).
//!
//! **Leaves** — no physics, no scene:
//! - [`error`]: the crate's error type, naming the file, line or setting at fault;
//! - [`rng`]: counter-based random streams keyed by (seed, domain, index);
//! - [`sampling`]: warps of uniform numbers (hemispheres, discrete distributions);
//! - [`parallel`]: deterministic chunked work sharing on a persistent pool;
//! - [`progress`]: the progress-reporting trait;
//! - [`files`]: checked reads, atomic writes and output checks;
//! - [`memory`]: the memory a render needs against what the machine has;
//! - [`geometry`]: triangles, the BVH, single-ray and 8-wide packet traversal;
//! - [`code_path`]: the SIMD kernels or their scalar twins, for traversal and photon lookups;
//! - [`traversal_choice`]: the traversal kernel per ray queue, chosen by timing the candidates;
//!
//! **Data** — records and their own methods:
//! - [`texture`]: image textures, bilinear lookups, sRGB decoding;
//! - [`optics`]: reflection, refraction and Fresnel at a smooth interface;
//! - [`microfacet`]: GGX rough conductors, dielectrics and Mitsuba's rough plastic with its coat
//!   tables (eval, pdf, visible-normal sampling);
//! - [`material`]: BSDFs (Lambert, glossy Phong, mirror, glass, thin glass, the rough ones) and their textures;
//! - [`medium`]: homogeneous participating media — transmittance, free-flight sampling, the
//!   Henyey–Greenstein phase function;
//! - [`photon_map`]: the 20-byte photon, the 8-wide photon tree, k-NN and fixed-radius density estimates;
//! - [`settings`]: the user's knobs, their layering and validation;
//! - [`scene`]: the scene model — triangles in BVH order, materials, lights (area, point, spot,
//!   directional, sun, environment), the camera, caustic targets, open edges;
//! - [`formats`]: every file reader, chosen from one table of extensions — the TOML scene file,
//!   Mitsuba XML, OBJ/MTL, PLY, glTF, images, built-in shapes — into the scene model;
//! - [`plan`] and [`effects`]: the effects plan — which terms and machinery a scene needs, and why;
//! - [`stats`]: plain records of what a render did (rays, times, maps, numerics);
//! - [`film`]: the five [`film::Term`]s per pixel, EXR and PNG output;
//! - [`job`]: one render's validated settings, plan and pass (seed, progressive radii);
//! - [`divided`]'s records: [`divided::pass_set`], which progressive passes a render runs (all, a
//!   range, worker K of N) and has run; [`divided::exact`], per-pixel fixed-point integer sums of
//!   passes, the same in any order; [`divided::pass_sums`], the mean, noise and bias of a set of
//!   passes from their exact sums;
//!
//! **Physics** — written once:
//! - [`transport`]: every vertex both engines and the path tracer share — camera samples,
//!   photon emission (caustic photons aimed at specular objects), deposit and scattering, direct
//!   light and its multiple importance sampling, gather and glossy rays, the specular
//!   continuation, density estimates, the random-stream layout;
//!
//! **Engines** — loops over the transport core:
//! - [`reference`](mod@reference): the scalar oracle, one ray at a time, that every fast path is tested against;
//! - [`wavefront`]: bevy_ecs systems over structure-of-arrays queues, SIMD kernels;
//! - [`path`]: an unbiased path tracer for checking energy;
//!
//! **Drivers and tools**:
//! - [`progressive`]: progressive passes with shrinking radii, a time budget and a stop request;
//! - [`divided::partial`] and [`divided::merge`]: partial films of divided or interrupted
//!   renders, and their exact merge;
//! - [`engine`]: the one render entry point — a single render or progressive passes;
//! - [`diagnostics`]: the diagnostic layers — estimate radii and photon counts per pixel;
//! - [`tools`] ([`tools::compare`], [`tools::sweep`], [`tools::plot`]), [`bench`](mod@bench), [`fuzzing`]:
//!   the CLI's `compare`, `sweep`, `bench` and the fuzz targets' entry points.

// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it is also true for NaN, so a
// NaN value is rejected by the same test as a non-positive one.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod bench;
pub mod code_path;
pub mod diagnostics;
pub mod divided;
pub mod effects;
pub mod engine;
pub mod error;
pub mod files;
pub mod film;
pub mod formats;
pub mod fuzzing;
pub mod geometry;
pub mod job;
pub mod material;
pub mod medium;
pub mod memory;
pub mod microfacet;
pub mod optics;
pub mod parallel;
pub mod path;
pub mod photon_map;
pub mod plan;
pub mod progress;
pub mod progressive;
pub mod reference;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod stats;
pub mod texture;
pub mod tools;
pub mod transport;
pub mod traversal_choice;
pub mod wavefront;

pub use error::{Error, Result};
