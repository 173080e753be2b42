//! Divided renders: a progressive render's passes split into sets rendered anywhere (another
//! thread count, another machine, another day) and summed into the undivided render, bit for
//! bit.
//!
//! Reads a [`crate::job::Job`]'s passes and the [`crate::film`]s they make; writes partial films
//! and merged images. In layer order: the records first — which passes a render runs
//! ([`pass_set`]), per-pixel fixed-point sums that do not depend on the order of addition
//! ([`exact`]), and the mean, noise and bias of a set of passes from those sums
//! ([`pass_sums`]), all below the physics, which the progressive driver uses — then the drivers
//! above the engines: partial films on disk ([`partial`]) and their merge ([`merge`]).
//! Why the merge is exact: docs/src/design/determinism.md.

pub mod exact;
pub mod merge;
pub mod partial;
pub mod pass_set;
pub mod pass_sums;
