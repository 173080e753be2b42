//! Structure-of-arrays queues: every ray or photon in flight is one lane, every field one column.
//! Kernels see plain slices; a bounce reads one queue and writes the next. Each queue is
//! declared once, with `soa_queue!`, from the fields of its work item (in the spirit of
//! pbrt-v4's `.soa` files), so every queue has the same `push`, `append`, `reserve`, `clear`
//! and `len`.
//!
//! Bytes per lane (why each field is there):
//! - rays: origin 12, direction 12 (f32 columns, as traversal reads them);
//! - hits: triangle 4 (u32::MAX = escaped), t 4, barycentrics 12 (all three, exactly as the
//!   triangle test returned them, so surface points match the reference engine's bit for bit);
//! - photons: path index 8, bounce 4, power 12, emitted power 4, specular-only flag 1 → 73 B a lane with ray and hit;
//! - camera-pass paths: sample 4, kind 1, sampler key 8, bounce base 1, depth 4, term 1,
//!   throughput 12, through-specular flag 1, MIS density 4 → 80 B a lane with ray and hit;
//! - shadow rays: sample 4, term 1, t_max 4, contribution 12, plus the ray.

use crate::film::Term;
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
    /// Reserves room for `n` more lanes.
    pub fn reserve(&mut self, n: usize) {
        for c in [&mut self.ox, &mut self.oy, &mut self.oz, &mut self.dx, &mut self.dy, &mut self.dz] {
            c.reserve(n);
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
    /// What an escaped lane's columns hold.
    const ESCAPED: Hit = Hit { tri: Self::MISS, t: f32::INFINITY, b: [0.0; 3] };

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
        for c in [&mut self.b0, &mut self.b1, &mut self.b2] {
            c.reserve(n);
        }
    }

    /// Appends `hits`, one per lane in order (`None`: escaped).
    pub fn extend(&mut self, hits: &[Option<Hit>]) {
        for h in hits {
            let h = h.unwrap_or(Self::ESCAPED);
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
    /// Lanes that hit nothing (listed for photons only: their leak count).
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

/// Declares a structure-of-arrays queue and its work item: the item is a struct with a ray
/// (`origin`, `dir`) and the given fields; the queue has the ray as [`RayColumns`], one `Vec`
/// column per field, and — with `+ hits` — the closest hits of its rays as [`HitColumns`]
/// (written by the intersect stage, so `push` and `append` leave them alone). Every queue gets
/// `len`, `is_empty`, `push`, `append`, `reserve` and `clear`.
macro_rules! soa_queue {
    (
        $(#[$qmeta:meta])* queue $queue:ident $(+ $hits:ident)?;
        $(#[$imeta:meta])* item $item:ident {
            $($(#[$fmeta:meta])* $field:ident: $ty:ty),* $(,)?
        }
    ) => {
        $(#[$imeta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $item {
            /// Ray origin.
            pub origin: glam::Vec3,
            /// Ray direction.
            pub dir: glam::Vec3,
            $($(#[$fmeta])* pub $field: $ty,)*
        }

        $(#[$qmeta])*
        #[derive(Clone, Debug, Default, PartialEq)]
        pub struct $queue {
            /// Rays, one per lane.
            pub rays: RayColumns,
            $(
                /// Closest hits of `rays`, one per lane, as the last intersect stage found them.
                pub $hits: HitColumns,
            )?
            $($(#[$fmeta])* pub $field: Vec<$ty>,)*
        }

        impl $queue {
            /// Number of lanes.
            #[must_use]
            pub fn len(&self) -> usize {
                self.rays.len()
            }
            /// True if no lane is queued.
            #[must_use]
            pub fn is_empty(&self) -> bool {
                self.rays.is_empty()
            }
            /// Appends a lane.
            #[inline]
            pub fn push(&mut self, item: $item) {
                self.rays.push(item.origin, item.dir);
                $(self.$field.push(item.$field);)*
            }
            /// Moves `other`'s lanes to the end (column copies).
            pub fn append(&mut self, other: &mut $queue) {
                self.rays.append(&mut other.rays);
                $(self.$field.append(&mut other.$field);)*
            }
            /// Reserves room for `n` more lanes.
            pub fn reserve(&mut self, n: usize) {
                self.rays.reserve(n);
                $(self.$field.reserve(n);)*
            }
            /// Removes every lane, keeping capacity.
            pub fn clear(&mut self) {
                self.rays.clear();
                $(self.$hits.clear();)?
                $(self.$field.clear();)*
            }
        }
    };
}

soa_queue! {
    /// Photons in flight.
    queue PhotonQueue + hits;
    /// One photon in flight.
    item PhotonLane {
        /// Path index (the reference engine's photon index).
        path: u64,
        /// Bounces so far.
        bounce: u32,
        /// Power per channel.
        power: Vec3,
        /// Largest channel of the path's emitted power (Russian roulette's reference).
        emitted: f32,
        /// True while every bounce so far was specular.
        specular_only: bool,
    }
}

impl PhotonQueue {
    /// Lane `i` as the transport core's photon ray.
    #[must_use]
    #[inline]
    pub fn photon(&self, i: usize) -> crate::transport::photon::PhotonRay {
        crate::transport::photon::PhotonRay {
            origin: self.rays.origin(i),
            dir: self.rays.direction(i),
            power: self.power[i],
            emitted: self.emitted[i],
            specular_only: self.specular_only[i],
        }
    }
}

/// What a camera-pass path segment is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum PathKind {
    /// A camera ray or its continuation through mirrors and glass.
    Camera = 0,
    /// A final-gather ray: reads the photon maps where it lands, unless it lands near.
    Gather = 1,
    /// A glossy-lobe ray: direct light, caustics and the global map where it lands.
    Glossy = 2,
    /// A gather ray that landed near its origin (secondary gather): direct light and caustics
    /// where it landed, and one more gather ray.
    NearGather = 3,
    /// The secondary gather's one more gather ray: reads the photon maps where it lands.
    SecondaryGather = 4,
    /// The ray of a narrow lobe where a gather or glossy ray landed (`transport::lobe`): the
    /// emission it finds and the photon maps where it lands.
    Lobe = 5,
}

impl PathKind {
    /// Reads the photon maps' radiance where it lands (a gather ray that did not land near, a
    /// narrow lobe's ray).
    #[must_use]
    pub fn reads_maps(self) -> bool {
        matches!(self, PathKind::Gather | PathKind::SecondaryGather | PathKind::Lobe)
    }
}

soa_queue! {
    /// Camera-pass path segments in flight.
    queue PathQueue + hits;
    /// One camera-pass path segment.
    item Segment {
        /// Sample (lane of the wave) the segment adds to.
        sample: u32,
        /// What the segment is for.
        kind: PathKind,
        /// Random stream key.
        key: u64,
        /// Bounce index of the first specular sample of this segment's chain.
        base: u8,
        /// Segments traced so far in this chain.
        depth: u32,
        /// Throughput (camera) or weight of what the segment finds (gather, glossy).
        beta: Vec3,
        /// Film term the segment's findings go to (gather, glossy).
        term: Term,
        /// True once a camera path went through a mirror or glass (for a gather or glossy
        /// ray: once the camera path it left had, so the emission it finds goes where that
        /// path's direct light went).
        through_specular: bool,
        /// A gather or glossy ray's density toward its direction at its origin (rays × pdf),
        /// which weighs the emission it hits straight away against light sampling
        /// (`transport::mis`); 0 where it adds none.
        mis: f32,
    }
}

soa_queue! {
    /// Shadow rays waiting for an any-hit test.
    queue ShadowQueue;
    /// One shadow ray.
    item ShadowLane {
        /// Blocked by hits with t below this.
        t_max: f32,
        /// Sample the light goes to.
        sample: u32,
        /// Film term.
        term: Term,
        /// Contribution when unblocked.
        contribution: Vec3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hit whose fields all say which lane it belongs to.
    fn hit(lane: usize) -> Option<Hit> {
        let f = lane as f32;
        (!lane.is_multiple_of(3)).then_some(Hit { tri: lane as u32, t: f, b: [f + 0.25, f + 0.5, f + 0.75] })
    }

    #[test]
    fn hits_written_in_chunks_fill_every_lane_in_order() {
        // 2 500 lanes in chunks of 1 024 (the last one short), after a longer bounce: the
        // columns are cleared and every lane written again.
        let mut hits = HitColumns::default();
        hits.extend(&(0..4_000).map(hit).collect::<Vec<_>>());
        hits.clear();
        for r in crate::wavefront::chunks(2_500, 1_024) {
            hits.extend(&r.map(hit).collect::<Vec<_>>());
        }
        assert_eq!(hits.tri.len(), 2_500);
        for lane in 0..2_500 {
            assert_eq!(hits.get(lane), hit(lane), "lane {lane}");
        }
        assert_eq!((hits.t[3], hits.b0[3]), (f32::INFINITY, 0.0), "a miss reads as escaped");
    }

    #[test]
    fn chunks_cover_every_lane_once() {
        let ranges: Vec<_> = crate::wavefront::chunks(2_500, 1_024).collect();
        assert_eq!(ranges, [0..1_024, 1_024..2_048, 2_048..2_500]);
        assert_eq!(crate::wavefront::chunks(0, 4).count(), 0);
    }
}
