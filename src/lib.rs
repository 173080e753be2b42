//! photonwave: a photon-mapping renderer (Jensen 1996).
//!
//! Reflected radiance splits into four terms, each computed the way that suits it: direct light
//! (light sampling with shadow rays), specular and glossy reflection (ray tracing), caustics
//! (caustic photon map) and soft indirect light (final gather over the global photon map).
//! [`reference`] is the scalar, one-ray-at-a-time renderer that every faster engine is tested
//! against.

// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it is also true for NaN, so a
// NaN value is rejected by the same test as a non-positive one.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bench;
pub mod compare;
pub mod effects;
pub mod engine;
pub mod error;
pub mod files;
pub mod film;
pub mod fuzzing;
pub mod geometry;
pub mod kernels;
pub mod material;
pub mod memory;
pub mod photon_map;
pub mod plan;
pub mod plot;
pub mod progressive;
pub mod reference;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod stats;
pub mod sweep;
pub mod wavefront;

pub use error::{Error, Result};
