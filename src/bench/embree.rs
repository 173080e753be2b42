//! `photonwave bench --features embree`: Intel Embree 3 (the system's `libembree3`, e.g. Debian's
//! `libembree-dev`) as the traversal yardstick, on the bench's own rays. Reads a scene's
//! triangle columns and the bench's ray sets; writes hit counts, which the bench times.
//!
//! The bindings are written here by hand from Embree 3.13's C headers (`rtcore_*.h`), only the
//! calls the bench needs: one triangle geometry in a HIGH-quality scene, and single rays
//! (`rtcIntersect1`, `rtcOccluded1`) and packets of 8 (`rtcIntersect8`, `rtcOccluded8`). This is
//! the crate's only `unsafe` code, and it is compiled only with the `embree` feature, which
//! nothing but the bench needs.

use crate::geometry::bvh::TriangleColumns;
use crate::geometry::RayQuery;
use std::ffi::c_void;

/// Embree's "no geometry" id (`RTC_INVALID_GEOMETRY_ID`).
const INVALID_ID: u32 = u32::MAX;

#[repr(C)]
struct Context {
    flags: u32,
    filter: *const c_void,
    inst_id: [u32; 1],
}

impl Context {
    /// What `rtcInitIntersectContext` writes (an inline function in the header, so not in the
    /// library): incoherent rays (flags 0), no filter, no instance.
    fn new() -> Self {
        Context { flags: 0, filter: std::ptr::null(), inst_id: [INVALID_ID] }
    }
}

/// `RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Ray1 {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `RTCHit`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Hit1 {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

/// `RTCRayHit`.
#[repr(C)]
struct RayHit1 {
    ray: Ray1,
    hit: Hit1,
}

/// `RTCRay8`: each field one column of eight lanes.
#[repr(C, align(32))]
#[derive(Default)]
struct Ray8 {
    org: [[f32; 8]; 3],
    tnear: [f32; 8],
    dir: [[f32; 8]; 3],
    time: [f32; 8],
    tfar: [f32; 8],
    mask: [u32; 8],
    id: [u32; 8],
    flags: [u32; 8],
}

/// `RTCHit8`.
#[repr(C, align(32))]
#[derive(Default)]
struct Hit8 {
    ng: [[f32; 8]; 3],
    u: [f32; 8],
    v: [f32; 8],
    prim_id: [u32; 8],
    geom_id: [u32; 8],
    inst_id: [[u32; 8]; 1],
}

/// The lane mask of `rtcIntersect8`/`rtcOccluded8`: −1 on, 0 off; Embree loads it as one
/// aligned 32-byte vector.
#[repr(C, align(32))]
struct Valid8([i32; 8]);

/// `RTCRayHit8`.
#[repr(C)]
#[derive(Default)]
struct RayHit8 {
    ray: Ray8,
    hit: Hit8,
}

type Handle = *mut c_void;

#[link(name = "embree3")]
extern "C" {
    fn rtcNewDevice(config: *const std::ffi::c_char) -> Handle;
    fn rtcReleaseDevice(device: Handle);
    fn rtcGetDeviceError(device: Handle) -> u32;
    fn rtcNewScene(device: Handle) -> Handle;
    fn rtcReleaseScene(scene: Handle);
    fn rtcSetSceneBuildQuality(scene: Handle, quality: u32);
    fn rtcSetSceneFlags(scene: Handle, flags: u32);
    fn rtcNewGeometry(device: Handle, kind: u32) -> Handle;
    fn rtcSetGeometryBuildQuality(geometry: Handle, quality: u32);
    fn rtcSetNewGeometryBuffer(
        geometry: Handle,
        kind: u32,
        slot: u32,
        format: u32,
        stride: usize,
        count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: Handle);
    fn rtcAttachGeometry(scene: Handle, geometry: Handle) -> u32;
    fn rtcReleaseGeometry(geometry: Handle);
    fn rtcCommitScene(scene: Handle);
    fn rtcIntersect1(scene: Handle, context: *mut Context, rayhit: *mut RayHit1);
    fn rtcOccluded1(scene: Handle, context: *mut Context, ray: *mut Ray1);
    fn rtcIntersect8(valid: *const i32, scene: Handle, context: *mut Context, rayhit: *mut RayHit8);
    fn rtcOccluded8(valid: *const i32, scene: Handle, context: *mut Context, ray: *mut Ray8);
}

/// `RTC_SCENE_FLAG_ROBUST`: traversal and triangle test without the optimisations that lose
/// accuracy (Embree's watertight mode).
const SCENE_FLAG_ROBUST: u32 = 1 << 2;
/// `RTC_BUILD_QUALITY_HIGH`: SAH with spatial splits.
const BUILD_QUALITY_HIGH: u32 = 2;
/// `RTC_GEOMETRY_TYPE_TRIANGLE`.
const GEOMETRY_TRIANGLE: u32 = 0;
/// `RTC_BUFFER_TYPE_INDEX`, `RTC_BUFFER_TYPE_VERTEX`.
const BUFFER_INDEX: u32 = 0;
const BUFFER_VERTEX: u32 = 1;
/// `RTC_FORMAT_UINT3`, `RTC_FORMAT_FLOAT3`.
const FORMAT_UINT3: u32 = 0x5003;
const FORMAT_FLOAT3: u32 = 0x9003;

/// The widest instruction set Embree may use: the widest this build was compiled for (AVX2 under
/// `.cargo/config.toml`'s x86-64-v3), so that both sides of the comparison run the same
/// instruction set. Left to itself Embree picks the widest the CPU has, AVX-512 on an Intel
/// Xeon, whose registers and mask instructions our `f32x8` code does not use.
#[must_use]
pub fn isa() -> &'static str {
    if cfg!(target_feature = "avx2") {
        "avx2"
    } else if cfg!(target_feature = "avx") {
        "avx"
    } else if cfg!(target_feature = "sse4.2") {
        "sse4.2"
    } else {
        "sse2"
    }
}

/// A committed Embree scene holding one triangle mesh: the scene's triangles, three unshared
/// vertices each, in the scene's order (Embree's primitive id is our triangle index).
pub struct EmbreeScene {
    device: Handle,
    scene: Handle,
}

// SAFETY: Embree's committed scenes may be traced from any number of threads at once
// (rtcIntersect*/rtcOccluded* are thread-safe after rtcCommitScene); nothing mutates it after.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Builds Embree's BVH over `tris` at HIGH quality, in its robust (watertight) mode if
    /// `robust`, on a device limited to [`isa`]; an error names Embree's error code.
    pub fn build(tris: TriangleColumns<'_>, robust: bool) -> Result<Self, String> {
        let n = tris.p0.len();
        if n == 0 {
            return Err("Embree: the scene has no triangles".into());
        }
        // SAFETY: each call gets handles Embree returned, checked non-null before use; the
        // buffers Embree allocates (uninitialised) are written through raw pointers within the
        // sizes asked for, before the geometry is committed.
        unsafe {
            let config = std::ffi::CString::new(format!("max_isa={}", isa())).expect("no NUL in the ISA name");
            let device = rtcNewDevice(config.as_ptr());
            if device.is_null() {
                return Err("Embree: rtcNewDevice failed (is libembree3 usable on this CPU?)".into());
            }
            let scene = rtcNewScene(device);
            if scene.is_null() {
                let code = rtcGetDeviceError(device);
                rtcReleaseDevice(device);
                return Err(format!("Embree: rtcNewScene failed (error {code})"));
            }
            let fail = |what: &str| {
                let code = rtcGetDeviceError(device);
                rtcReleaseScene(scene);
                rtcReleaseDevice(device);
                Err(format!("Embree: {what} (error {code})"))
            };
            rtcSetSceneBuildQuality(scene, BUILD_QUALITY_HIGH);
            if robust {
                rtcSetSceneFlags(scene, SCENE_FLAG_ROBUST);
            }
            let geometry = rtcNewGeometry(device, GEOMETRY_TRIANGLE);
            if geometry.is_null() {
                return fail("rtcNewGeometry failed");
            }
            rtcSetGeometryBuildQuality(geometry, BUILD_QUALITY_HIGH);
            let vertices = rtcSetNewGeometryBuffer(geometry, BUFFER_VERTEX, 0, FORMAT_FLOAT3, 12, 3 * n);
            let indices = rtcSetNewGeometryBuffer(geometry, BUFFER_INDEX, 0, FORMAT_UINT3, 12, n);
            if vertices.is_null() || indices.is_null() {
                rtcReleaseGeometry(geometry);
                return fail(&format!("buffers of {n} triangles refused"));
            }
            let (v, idx) = (vertices.cast::<f32>(), indices.cast::<u32>());
            for i in 0..n {
                for (k, p) in [tris.p0[i], tris.p1[i], tris.p2[i]].into_iter().enumerate() {
                    for a in 0..3 {
                        v.add(9 * i + 3 * k + a).write(p[a]);
                    }
                    idx.add(3 * i + k).write((3 * i + k) as u32);
                }
            }
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(scene, geometry);
            rtcReleaseGeometry(geometry);
            rtcCommitScene(scene);
            if rtcGetDeviceError(device) != 0 {
                return fail("building the scene failed");
            }
            Ok(EmbreeScene { device, scene })
        }
    }

    /// Rays of `rays` that hit anything closer than their t_max, one `rtcIntersect1` (closest)
    /// or `rtcOccluded1` (any) per ray.
    #[must_use]
    pub fn count_single(&self, rays: &[RayQuery], any: bool) -> usize {
        let mut ctx = Context::new();
        let mut hits = 0;
        for q in rays {
            let ray = Ray1 {
                org: q.origin.to_array(),
                tnear: 0.0,
                dir: q.direction.to_array(),
                time: 0.0,
                tfar: q.t_max,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            };
            let hit =
                Hit1 { ng: [0.0; 3], u: 0.0, v: 0.0, prim_id: INVALID_ID, geom_id: INVALID_ID, inst_id: [INVALID_ID] };
            let mut rh = RayHit1 { ray, hit };
            // SAFETY: a committed scene, an initialised context and ray of Embree's layout.
            unsafe {
                if any {
                    rtcOccluded1(self.scene, &raw mut ctx, &raw mut rh.ray);
                } else {
                    rtcIntersect1(self.scene, &raw mut ctx, &raw mut rh);
                }
            }
            // Occluded rays come back with tfar = −∞; hits with a geometry id.
            hits += usize::from(if any { rh.ray.tfar < 0.0 } else { rh.hit.geom_id != INVALID_ID });
        }
        hits
    }

    /// As [`Self::count_single`], eight rays at a time (`rtcIntersect8`, `rtcOccluded8`; a last
    /// packet of fewer rays has its other lanes switched off).
    #[must_use]
    pub fn count_packets(&self, rays: &[RayQuery], any: bool) -> usize {
        let mut ctx = Context::new();
        let mut hits = 0;
        let mut rh = RayHit8::default();
        for chunk in rays.chunks(8) {
            let mut valid = Valid8([0; 8]);
            for (lane, q) in chunk.iter().enumerate() {
                valid.0[lane] = -1;
                for a in 0..3 {
                    rh.ray.org[a][lane] = q.origin[a];
                    rh.ray.dir[a][lane] = q.direction[a];
                }
                rh.ray.tnear[lane] = 0.0;
                rh.ray.tfar[lane] = q.t_max;
                rh.ray.mask[lane] = u32::MAX;
                rh.hit.geom_id[lane] = INVALID_ID;
                rh.hit.inst_id[0][lane] = INVALID_ID;
            }
            // SAFETY: as in count_single; `valid` (32-byte aligned, as Embree loads it) switches
            // off lanes past the chunk's end.
            unsafe {
                if any {
                    rtcOccluded8(valid.0.as_ptr(), self.scene, &raw mut ctx, &raw mut rh.ray);
                } else {
                    rtcIntersect8(valid.0.as_ptr(), self.scene, &raw mut ctx, &raw mut rh);
                }
            }
            hits += (0..chunk.len())
                .filter(|&l| if any { rh.ray.tfar[l] < 0.0 } else { rh.hit.geom_id[l] != INVALID_ID })
                .count();
        }
        hits
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: handles from build, released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn layouts_match_embrees_headers() {
        // Sizes from rtcore_ray.h with RTC_MAX_INSTANCE_LEVEL_COUNT = 1.
        assert_eq!(std::mem::size_of::<Ray1>(), 48);
        assert_eq!(std::mem::size_of::<Hit1>(), 32);
        assert_eq!(std::mem::size_of::<RayHit1>(), 80);
        assert_eq!(std::mem::size_of::<Ray8>(), 384);
        assert_eq!(std::mem::size_of::<Hit8>(), 256);
        // RTCIntersectContext: flags, padding, filter pointer, instID[1], padding.
        assert_eq!(std::mem::size_of::<Context>(), 24);
        // RTC_ALIGN(16) and RTC_ALIGN(32); the 8-ray calls load the lane mask as one aligned
        // 32-byte vector.
        assert_eq!(std::mem::align_of::<RayHit1>(), 16);
        assert_eq!(std::mem::align_of::<RayHit8>(), 32);
        assert_eq!(std::mem::align_of::<Valid8>(), 32);
    }

    #[test]
    fn one_triangle_is_hit_through_its_middle_and_missed_beside_it_in_both_modes() {
        let (p0, p1, p2) = ([Vec3::new(0.0, 0.0, 1.0)], [Vec3::new(1.0, 0.0, 1.0)], [Vec3::new(0.0, 1.0, 1.0)]);
        for robust in [false, true] {
            let e = EmbreeScene::build(TriangleColumns::new(&p0, &p1, &p2), robust).unwrap();
            let rays = [
                RayQuery::new(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, f32::INFINITY),
                RayQuery::new(Vec3::new(0.9, 0.9, 0.0), Vec3::Z, f32::INFINITY),
                RayQuery::new(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 0.5),
            ];
            for any in [false, true] {
                assert_eq!(e.count_single(&rays, any), 1);
                assert_eq!(e.count_packets(&rays, any), 1);
            }
        }
    }
}
