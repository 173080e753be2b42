//! Structure-of-arrays queues: every ray or photon in flight is one lane, every field one column.
//! Kernels see plain slices; a bounce reads one queue and writes the next.
//!
//! Bytes per lane (why each field is there):
//! - rays: origin 12, direction 12 (f32 columns, as traversal reads them);
//! - hits: triangle 4 (u32::MAX = escaped), t 4, barycentrics 12 (all three, exactly as the
//!   triangle test returned them, so surface points match the reference engine's bit for bit);
//! - photons: path index 8, bounce 4, power 12, specular-only flag 1 → 61 B a lane with ray and hit;
//! - camera-pass paths: sample 4, kind 1, sampler key 8, bounce base 1, depth 4, term slot 1,
//!   throughput 12, through-specular flag 1 → 64 B a lane with ray and hit;
//! - shadow rays: sample 4, slot 1, t_max 4, contribution 12, plus the ray.

use crate::geometry::Hit;
use glam::Vec3;

/// Ray origins and directions as six f32 columns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayColumns {
    /// Origin x.
    pub ox: Vec<f32>,
    /// Origin y.
    pub oy: Vec<f32>,
    /// Origin z.
    pub oz: Vec<f32>,
    /// Direction x.
    pub dx: Vec<f32>,
    /// Direction y.
    pub dy: Vec<f32>,
    /// Direction z.
    pub dz: Vec<f32>,
}

impl RayColumns {
    /// Appends a ray.
    pub fn push(&mut self, o: Vec3, d: Vec3) {
        self.ox.push(o.x);
        self.oy.push(o.y);
        self.oz.push(o.z);
        self.dx.push(d.x);
        self.dy.push(d.y);
        self.dz.push(d.z);
    }
    /// Origin of lane `i`.
    #[inline]
    #[must_use]
    pub fn origin(&self, i: usize) -> Vec3 {
        Vec3::new(self.ox[i], self.oy[i], self.oz[i])
    }
    /// Direction of lane `i`.
    #[inline]
    #[must_use]
    pub fn direction(&self, i: usize) -> Vec3 {
        Vec3::new(self.dx[i], self.dy[i], self.dz[i])
    }
    /// Number of lanes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.ox.len()
    }
    /// True if empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ox.is_empty()
    }
    /// Removes every lane, keeping capacity.
    pub fn clear(&mut self) {
        for c in [&mut self.ox, &mut self.oy, &mut self.oz, &mut self.dx, &mut self.dy, &mut self.dz] {
            c.clear();
        }
    }
    /// Moves `other`'s lanes to the end (column copies).
    pub fn append(&mut self, other: &mut RayColumns) {
        self.ox.append(&mut other.ox);
        self.oy.append(&mut other.oy);
        self.oz.append(&mut other.oz);
        self.dx.append(&mut other.dx);
        self.dy.append(&mut other.dy);
        self.dz.append(&mut other.dz);
    }
}

/// Closest hits as columns, one per lane of the queue that was intersected.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HitColumns {
    /// Triangle, or [`HitColumns::MISS`].
    pub tri: Vec<u32>,
    /// Distance.
    pub t: Vec<f32>,
    /// Barycentric of p1.
    pub b1: Vec<f32>,
    /// Barycentric of p2.
    pub b2: Vec<f32>,
    /// Barycentric of p0 as the triangle test computed it.
    pub b0: Vec<f32>,
}

impl HitColumns {
    /// Marks an escaped lane.
    pub const MISS: u32 = u32::MAX;

    /// Removes every lane.
    pub fn clear(&mut self) {
        self.tri.clear();
        self.t.clear();
        self.b0.clear();
        self.b1.clear();
        self.b2.clear();
    }

    /// Reserves room for `n` more lanes.
    pub fn reserve(&mut self, n: usize) {
        self.tri.reserve(n);
        self.t.reserve(n);
        self.b0.reserve(n);
        self.b1.reserve(n);
        self.b2.reserve(n);
    }

    /// Moves `other`'s lanes to the end (column copies).
    pub fn append(&mut self, other: &mut HitColumns) {
        self.tri.append(&mut other.tri);
        self.t.append(&mut other.t);
        self.b0.append(&mut other.b0);
        self.b1.append(&mut other.b1);
        self.b2.append(&mut other.b2);
    }

    /// Appends `hits`.
    pub fn extend(&mut self, hits: impl Iterator<Item = Option<Hit>>) {
        for h in hits {
            let h = h.unwrap_or(Hit { tri: Self::MISS, t: f32::INFINITY, b: [0.0; 3] });
            self.tri.push(h.tri);
            self.t.push(h.t);
            self.b0.push(h.b[0]);
            self.b1.push(h.b[1]);
            self.b2.push(h.b[2]);
        }
    }
    /// The hit of lane `i`, if any.
    #[inline]
    #[must_use]
    pub fn get(&self, i: usize) -> Option<Hit> {
        (self.tri[i] != Self::MISS).then(|| Hit {
            tri: self.tri[i],
            t: self.t[i],
            b: [self.b0[i], self.b1[i], self.b2[i]],
        })
    }
}

/// Lanes of the last intersected queue, split by what happens next.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Classified {
    /// Lanes that hit a diffuse or glossy surface.
    pub diffuse: Vec<u32>,
    /// Lanes that hit a mirror.
    pub mirror: Vec<u32>,
    /// Lanes that hit glass.
    pub glass: Vec<u32>,
    /// Lanes that hit nothing.
    pub escaped: Vec<u32>,
}

impl Classified {
    /// Empties every list.
    pub fn clear(&mut self) {
        self.diffuse.clear();
        self.mirror.clear();
        self.glass.clear();
        self.escaped.clear();
    }
}

/// Photons in flight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonQueue {
    /// Rays.
    pub rays: RayColumns,
    /// Closest hits of `rays`.
    pub hits: HitColumns,
    /// Path index (the reference engine's photon index).
    pub path: Vec<u64>,
    /// Bounces so far.
    pub bounce: Vec<u32>,
    /// Power per channel.
    pub power: Vec<Vec3>,
    /// 1 while every bounce so far was specular.
    pub specular_only: Vec<u8>,
}

impl PhotonQueue {
    /// Number of lanes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.path.len()
    }
    /// True if empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.path.is_empty()
    }
    /// Appends a lane.
    pub fn push(&mut self, o: Vec3, d: Vec3, path: u64, bounce: u32, power: Vec3, specular_only: bool) {
        self.rays.push(o, d);
        self.path.push(path);
        self.bounce.push(bounce);
        self.power.push(power);
        self.specular_only.push(specular_only as u8);
    }
    /// Removes every lane.
    pub fn clear(&mut self) {
        self.rays.clear();
        self.path.clear();
        self.bounce.clear();
        self.power.clear();
        self.specular_only.clear();
    }
    /// Moves `other`'s lanes (rays and their columns, not hits) to the end.
    pub fn append(&mut self, other: &mut PhotonQueue) {
        self.rays.append(&mut other.rays);
        self.path.append(&mut other.path);
        self.bounce.append(&mut other.bounce);
        self.power.append(&mut other.power);
        self.specular_only.append(&mut other.specular_only);
    }
}

/// What a camera-pass path segment is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum PathKind {
    /// A camera ray or its continuation through mirrors and glass.
    Camera = 0,
    /// A final-gather ray: reads the photon maps where it lands.
    Gather = 1,
    /// A glossy-lobe ray: direct light, caustics and the global map where it lands.
    Glossy = 2,
}

/// Camera-pass path segments in flight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathQueue {
    /// Rays.
    pub rays: RayColumns,
    /// Closest hits of `rays`.
    pub hits: HitColumns,
    /// Sample (lane of the wave) the segment adds to.
    pub sample: Vec<u32>,
    /// [`PathKind`].
    pub kind: Vec<PathKind>,
    /// Random stream key.
    pub key: Vec<u64>,
    /// Bounce index of the first specular sample of this segment's chain.
    pub base: Vec<u8>,
    /// Segments traced so far in this chain.
    pub depth: Vec<u32>,
    /// Throughput (camera) or weight of what the segment finds (gather, glossy).
    pub beta: Vec<Vec3>,
    /// Film term the segment's findings go to (gather, glossy), see [`crate::film::TERM_NAMES`].
    pub slot: Vec<u8>,
    /// 1 once a camera path went through a mirror or glass.
    pub through_specular: Vec<u8>,
}

/// One segment to enqueue.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    /// Origin.
    pub o: Vec3,
    /// Direction.
    pub d: Vec3,
    /// Sample.
    pub sample: u32,
    /// Kind.
    pub kind: PathKind,
    /// Random stream key.
    pub key: u64,
    /// Bounce base.
    pub base: u8,
    /// Depth.
    pub depth: u32,
    /// Throughput or weight.
    pub beta: Vec3,
    /// Film term.
    pub slot: u8,
    /// Through-specular flag.
    pub through_specular: bool,
}

impl PathQueue {
    /// Number of lanes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.sample.len()
    }
    /// True if empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.sample.is_empty()
    }
    /// Reserves room for `n` more lanes.
    pub fn reserve(&mut self, n: usize) {
        for c in [
            &mut self.rays.ox,
            &mut self.rays.oy,
            &mut self.rays.oz,
            &mut self.rays.dx,
            &mut self.rays.dy,
            &mut self.rays.dz,
        ] {
            c.reserve(n);
        }
        self.sample.reserve(n);
        self.kind.reserve(n);
        self.key.reserve(n);
        self.base.reserve(n);
        self.depth.reserve(n);
        self.beta.reserve(n);
        self.slot.reserve(n);
        self.through_specular.reserve(n);
    }

    /// Moves `other`'s lanes to the end (column copies; hits are not moved).
    pub fn append(&mut self, other: &mut PathQueue) {
        self.rays.append(&mut other.rays);
        self.sample.append(&mut other.sample);
        self.kind.append(&mut other.kind);
        self.key.append(&mut other.key);
        self.base.append(&mut other.base);
        self.depth.append(&mut other.depth);
        self.beta.append(&mut other.beta);
        self.slot.append(&mut other.slot);
        self.through_specular.append(&mut other.through_specular);
    }

    /// Appends a segment.
    pub fn push(&mut self, s: Segment) {
        self.rays.push(s.o, s.d);
        self.sample.push(s.sample);
        self.kind.push(s.kind);
        self.key.push(s.key);
        self.base.push(s.base);
        self.depth.push(s.depth);
        self.beta.push(s.beta);
        self.slot.push(s.slot);
        self.through_specular.push(s.through_specular as u8);
    }
    /// Removes every lane.
    pub fn clear(&mut self) {
        self.rays.clear();
        self.sample.clear();
        self.kind.clear();
        self.key.clear();
        self.base.clear();
        self.depth.clear();
        self.beta.clear();
        self.slot.clear();
        self.through_specular.clear();
    }
}

/// Shadow rays waiting for an any-hit test.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowQueue {
    /// Rays.
    pub rays: RayColumns,
    /// Blocked by hits with t below this.
    pub t_max: Vec<f32>,
    /// Sample the light goes to.
    pub sample: Vec<u32>,
    /// Film term.
    pub slot: Vec<u8>,
    /// Contribution when unblocked.
    pub contribution: Vec<Vec3>,
}

impl ShadowQueue {
    /// Number of lanes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.sample.len()
    }
    /// True if empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.sample.is_empty()
    }
    /// Moves `other`'s lanes to the end (column copies).
    pub fn append(&mut self, other: &mut ShadowQueue) {
        self.rays.append(&mut other.rays);
        self.t_max.append(&mut other.t_max);
        self.sample.append(&mut other.sample);
        self.slot.append(&mut other.slot);
        self.contribution.append(&mut other.contribution);
    }

    /// Appends a shadow ray.
    pub fn push(&mut self, o: Vec3, d: Vec3, t_max: f32, sample: u32, slot: u8, contribution: Vec3) {
        self.rays.push(o, d);
        self.t_max.push(t_max);
        self.sample.push(sample);
        self.slot.push(slot);
        self.contribution.push(contribution);
    }
    /// Removes every lane.
    pub fn clear(&mut self) {
        self.rays.clear();
        self.t_max.clear();
        self.sample.clear();
        self.slot.clear();
        self.contribution.clear();
    }
}
