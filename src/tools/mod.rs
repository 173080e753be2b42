//! The command line's measuring tools, clients of the engines: `compare` (how far an image is
//! from a reference, per layer, and with `local` per block and in speckled pixels), `sweep` (a
//! grid of settings rendered, timed and measured: what accuracy costs in time) and the plots
//! `sweep` draws.
//!
//! Reads rendered films and a scene; writes CSV, JSON and SVG/PNG plots. Nothing here is used
//! by a render.

pub mod compare;
pub mod local;
pub mod plot;
pub mod sweep;
