//! Geometry: watertight ray/triangle intersection, robust ray origins, and the obvhs BVH.

pub mod bvh;
pub mod cut_out;
pub mod offset;
pub mod packet;
pub mod sah;
pub mod slab;
pub mod traverse;
pub mod triangle;
pub mod triangle8;
pub mod wide;
pub mod wide_collapse;
pub mod wide_packet;
pub mod wide_traverse;

pub use bvh::{Bvh, Hit};
pub use offset::{gamma, offset_ray_origin};
pub use traverse::RayQuery;
pub use triangle::{in_range, intersect_triangle, normal_and_area, MAX_COORDINATE};
