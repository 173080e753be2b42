//! The implicit balanced kd-tree: building it (the median of each index range is its node,
//! split along the range's longest extent) and walking it toward a query point under a
//! shrinking radius.

use super::{Photon, PhotonMap, BUCKET};
use glam::Vec3;

impl PhotonMap {
    /// Walks the implicit tree, calling `visit(lo, hi, simd_ok, r2)` for every bucket (`simd_ok`
    /// true) and every inner node's photon (a range of one, `simd_ok` false) that can lie within
    /// the (shrinking) radius² `r2`.
    pub(super) fn walk(&self, p: Vec3, r2: &mut f32, mut visit: impl FnMut(usize, usize, bool, &mut f32)) {
        // Explicit stack of index ranges, each with the squared distance from `p` to the
        // splitting plane that separated it (0 for ranges on p's side): a far range is skipped
        // when r² has since shrunk below it.
        let mut stack: [(u32, u32, f32); 64] = [(0, 0, 0.0); 64];
        let mut top = 1;
        stack[0] = (0, self.len as u32, 0.0);
        while top > 0 {
            top -= 1;
            let (mut lo, mut hi, plane2) = stack[top];
            if plane2 >= *r2 {
                continue;
            }
            while lo < hi {
                if (hi - lo) as usize <= BUCKET {
                    visit(lo as usize, hi as usize, true, r2);
                    break;
                }
                let mid = lo + (hi - lo) / 2;
                let m = mid as usize;
                let a = self.axis(m);
                let q = [self.x[m], self.y[m], self.z[m]][a];
                let delta = p[a] - q;
                visit(m, m + 1, false, r2);
                // Descend into p's side now; remember the other side.
                let (near, far) = if delta < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
                if far.0 < far.1 && delta * delta < *r2 && top < stack.len() {
                    stack[top] = (far.0, far.1, delta * delta);
                    top += 1;
                }
                (lo, hi) = near;
            }
        }
    }

    #[inline]
    pub(super) fn axis(&self, i: usize) -> usize {
        (self.key[i] >> 14 & 3) as usize
    }

    /// Squared distance of photon `i` from `p`: the same operations as the 8-wide form.
    #[inline]
    pub(super) fn d2(&self, i: usize, p: Vec3) -> f32 {
        let (dx, dy, dz) = (self.x[i] - p.x, self.y[i] - p.y, self.z[i] - p.z);
        dx * dx + dy * dy + dz * dz
    }
}

pub(super) fn build_range(photons: &mut [Photon], axis: &mut [u8], lo: usize, hi: usize) {
    if hi - lo <= BUCKET {
        return;
    }
    let mut mn = Vec3::splat(f32::INFINITY);
    let mut mx = Vec3::splat(f32::NEG_INFINITY);
    for ph in &photons[lo..hi] {
        mn = mn.min(ph.position);
        mx = mx.max(ph.position);
    }
    let ext = mx - mn;
    let a = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = lo + (hi - lo) / 2;
    photons[lo..hi].select_nth_unstable_by(mid - lo, |x, y| x.position[a].total_cmp(&y.position[a]));
    axis[mid] = a as u8;
    build_range(photons, axis, lo, mid);
    build_range(photons, axis, mid + 1, hi);
}
