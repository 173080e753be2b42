//! Light portals: parallelograms marking where the environment's light enters an interior (a
//! window, a door), as pbrt-v4's portal infinite light and Cycles' portal lamps mark them. Reads
//! the portals' corners; writes directions toward the environment drawn through them and the
//! density of that draw, which direct light mixes with its cosine-weighted half
//! ([`super::Scene::sample_incident`]) and MIS weighs BSDF rays against (`transport::mis`).
//!
//! A direction from x is drawn by picking a portal in proportion to its area and a point
//! uniformly on it, so its density toward unit ω is
//! Σₖ (Aₖ/A)·(1/Aₖ)·tₖ²/|cos θₖ| = Σₖ tₖ² / (A·|cos θₖ|), over the portals k that the ray x + tω
//! crosses (at tₖ > 0, θₖ its angle to portal k's normal), A the portals' total area. A
//! direction that crosses no portal has density 0 here; the cosine-weighted half and the BSDF
//! rays still find it, so a portal that misses a window costs noise, not bias.
//!
//! Photons: a share of the environment's photons travel lines drawn through the portals
//! ([`Portals::sample_line`]), the rest the disk across the whole scene, and each carries the
//! radiance over the two strategies' mixed density at its line ([`Portals::line_density`] and
//! the disk's), so lines through no portal keep their light and the maps' expectation is the
//! disk's alone ([`super::Scene::sample_emission`]).

use crate::sampling::{cosine_hemisphere, Distribution1D, Frame, ONE_BELOW};
use glam::Vec3;

/// One portal: the parallelogram `corner + a·e1 + b·e2`, a and b in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    corner: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// Unit normal (e1 × e2 normalised).
    normal: Vec3,
    /// The dual basis of (e1, e2) in its plane: a = (q − corner)·d1, b = (q − corner)·d2.
    d1: Vec3,
    d2: Vec3,
    area: f32,
}

impl Portal {
    /// The portal with these four corners, in order around it. `Err` says why they make none:
    /// not finite, not a parallelogram (the third corner farther than 10⁻³ of its longer side
    /// from where the other three put it), or of zero area.
    pub fn new(corners: [Vec3; 4]) -> Result<Portal, String> {
        if !corners.iter().all(|c| c.is_finite()) {
            return Err("its corners must be finite".into());
        }
        let [c0, c1, c2, c3] = corners;
        let (e1, e2) = (c1 - c0, c3 - c0);
        let off = (c2 - (c0 + e1 + e2)).length();
        let side = e1.length().max(e2.length());
        if off > 1e-3 * side {
            return Err(format!(
                "its four corners, in order around it, must make a parallelogram (a rectangle for a window): the \
                 third is {off} from where the others put it"
            ));
        }
        let cross = e1.cross(e2);
        let area = cross.length();
        if !(area > 0.0 && area.is_finite()) {
            return Err("it has zero area".into());
        }
        let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = g11 * g22 - g12 * g12;
        Ok(Portal {
            corner: c0,
            e1,
            e2,
            normal: cross / area,
            d1: (e1 * g22 - e2 * g12) / det,
            d2: (e2 * g11 - e1 * g12) / det,
            area,
        })
    }

    /// The same portal with its corner given relative to `origin` (the scene's frame).
    #[must_use]
    pub fn moved(self, origin: Vec3) -> Portal {
        Portal { corner: (self.corner.as_dvec3() - origin.as_dvec3()).as_vec3(), ..self }
    }

    /// Where the ray `x + t·w` (unit `w`) crosses the portal: (t, |cos θ|), or `None`.
    fn crossing(&self, x: Vec3, w: Vec3) -> Option<(f32, f32)> {
        let cos = w.dot(self.normal);
        if cos == 0.0 {
            return None;
        }
        let t = (self.corner - x).dot(self.normal) / cos;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let q = x + w * t - self.corner;
        let (a, b) = (q.dot(self.d1), q.dot(self.d2));
        ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some((t, cos.abs()))
    }
}

/// The scene's portals and the area distribution that picks one.
#[derive(Clone, Debug, Default)]
pub struct Portals {
    list: Vec<Portal>,
    /// Picks a portal by area (`None` without portals).
    by_area: Option<Distribution1D>,
}

impl Portals {
    /// The portals `list` (none: an empty set, which samples nothing).
    #[must_use]
    pub fn new(list: Vec<Portal>) -> Portals {
        let areas: Vec<f64> = list.iter().map(|p| f64::from(p.area)).collect();
        Portals { by_area: Distribution1D::try_new(&areas), list }
    }

    /// Whether there is none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// How many there are.
    #[must_use]
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Their total area.
    #[must_use]
    pub fn area(&self) -> f32 {
        self.by_area.as_ref().map_or(0.0, |d| d.total() as f32)
    }

    /// The same portals relative to `origin` (the scene's frame).
    #[must_use]
    pub fn moved(&self, origin: Vec3) -> Portals {
        Portals { list: self.list.iter().map(|p| p.moved(origin)).collect(), by_area: self.by_area.clone() }
    }

    /// A portal picked by area and a point uniform on it, from two uniform numbers; `None`
    /// without portals.
    fn point(&self, u: [f32; 2]) -> Option<(&Portal, Vec3)> {
        let (k, a) = self.by_area.as_ref()?.sample_remapped(u[0]);
        let p = &self.list[k];
        Some((p, p.corner + p.e1 * a + p.e2 * u[1]))
    }

    /// A unit direction from `x` through a point of a portal (picked by area, the point uniform
    /// on it) with two uniform numbers; `None` without portals or for `x` on the point.
    #[must_use]
    pub fn sample(&self, x: Vec3, u: [f32; 2]) -> Option<Vec3> {
        let d = self.point(u)?.1 - x;
        let len = d.length();
        (len > 0.0 && len.is_finite()).then(|| d / len)
    }

    /// A line of light through a portal, for a photon: a portal and a point on it
    /// (by area, uniform on it, from `u[2]` and `u[3]`), and a unit direction of travel
    /// cosine-weighted about its normal, to either side with equal chance (which side is inside
    /// is not known): (the point, the direction). `None` without portals.
    #[must_use]
    pub fn sample_line(&self, u: [f32; 4]) -> Option<(Vec3, Vec3)> {
        let (p, y) = self.point([u[2], u[3]])?;
        let (side, u0) = if u[0] < 0.5 { (p.normal, 2.0 * u[0]) } else { (-p.normal, 2.0 * u[0] - 1.0) };
        let local = cosine_hemisphere([u0.min(ONE_BELOW), u[1]]);
        Some((y, Frame::new(side).to_world(local)))
    }

    /// The density of [`Portals::sample_line`]'s lines at the line `o + t·w` (unit `w`), per
    /// steradian and unit area across the line: for each portal it crosses, (Aₖ/A)·(1/Aₖ)·
    /// (|cos θₖ|/2π) per unit of the portal's area, which is |cos θₖ| of the area across, so
    /// (portals crossed)/(2π·A). `o` must lie before every portal on the line (outside the
    /// scene).
    #[must_use]
    pub fn line_density(&self, o: Vec3, w: Vec3) -> f32 {
        let crossed = self.list.iter().filter(|p| p.crossing(o, w).is_some()).count();
        if crossed == 0 {
            0.0
        } else {
            crossed as f32 / (2.0 * std::f32::consts::PI * self.area())
        }
    }

    /// The density of [`Portals::sample`] toward unit `w` from `x`, per steradian: Σₖ tₖ² /
    /// (A·|cos θₖ|) over the portals the ray crosses (0 where it crosses none).
    #[must_use]
    pub fn pdf(&self, x: Vec3, w: Vec3) -> f32 {
        let total = self.area();
        let sum: f32 = self.list.iter().filter_map(|p| p.crossing(x, w)).map(|(t, cos)| t * t / cos).sum();
        if sum > 0.0 {
            sum / total
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform numbers from a fixed-seed generator (splitmix64).
    fn uniforms(k: u64) -> [f32; 2] {
        let mix = |mut z: u64| {
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        };
        let z = (k + 1).wrapping_mul(0x9e3779b97f4a7c15);
        [mix(z), mix(z ^ 0x5555)]
    }

    fn window(x0: f32, x1: f32, y0: f32, y1: f32, z: f32) -> Portal {
        Portal::new([Vec3::new(x0, y0, z), Vec3::new(x1, y0, z), Vec3::new(x1, y1, z), Vec3::new(x0, y1, z)]).unwrap()
    }

    /// The solid angle of an axis-aligned rectangle [0, a] × [0, b] at distance d, seen from a
    /// point above its corner: atan(ab / (d·√(a² + b² + d²))).
    fn corner_solid_angle(a: f64, b: f64, d: f64) -> f64 {
        (a * b / (d * (a * a + b * b + d * d).sqrt())).atan()
    }

    #[test]
    fn samples_cross_their_portal_and_their_density_integrates_to_the_solid_angle() {
        // Two windows seen from x: the mean of 1/pdf over the draws is the solid angle they
        // subtend (each draw crosses one of them, so pdf > 0), exact from the corner formula;
        // within 4 standard errors of n = 200 000 draws.
        let portals = Portals::new(vec![window(0.0, 1.0, 0.0, 0.5, -2.0), window(-1.5, -0.5, 0.0, 1.0, -1.0)]);
        let x = Vec3::ZERO;
        let want =
            corner_solid_angle(1.0, 0.5, 2.0) + (corner_solid_angle(1.5, 1.0, 1.0) - corner_solid_angle(0.5, 1.0, 1.0));
        let n = 200_000u64;
        let v: Vec<f64> = (0..n)
            .map(|k| {
                let w = portals.sample(x, uniforms(k)).unwrap();
                let pdf = portals.pdf(x, w);
                assert!(pdf > 0.0, "draw {k} toward {w} crosses no portal");
                1.0 / f64::from(pdf)
            })
            .collect();
        let mean = v.iter().sum::<f64>() / n as f64;
        let se = (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1) as f64 / n as f64).sqrt();
        assert!((mean - want).abs() < 4.0 * se, "∫ dω = {mean} ± {se}, want {want}");
        // Directions that cross no portal have density 0; the portals' frame moves with the scene.
        assert_eq!(portals.pdf(x, Vec3::Z), 0.0);
        let moved = portals.moved(Vec3::new(0.0, 0.0, -1.0));
        for w in [Vec3::new(0.2, 0.2, -1.0), Vec3::new(-1.0, 0.5, -1.0)] {
            let (w, here) = (w.normalize(), Vec3::new(0.0, 0.0, 1.0));
            let (a, b) = (portals.pdf(x, w), moved.pdf(here, w));
            assert!(a > 0.0 && (a - b).abs() <= 1e-5 * a, "{a} against {b}");
        }
    }

    #[test]
    fn corners_that_make_no_parallelogram_are_refused() {
        let c = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        assert!(Portal::new([c(0.0, 0.0), c(1.0, 0.0), c(1.0, 1.0), c(0.0, 1.0)]).is_ok());
        let skew = Portal::new([c(0.0, 0.0), c(1.0, 0.0), c(1.3, 1.0), c(0.0, 1.0)]).unwrap_err();
        assert!(skew.contains("parallelogram"), "{skew}");
        let flat = Portal::new([c(0.0, 0.0), c(1.0, 0.0), c(2.0, 0.0), c(1.0, 0.0)]).unwrap_err();
        assert!(flat.contains("zero area"), "{flat}");
        assert!(Portal::new([c(0.0, 0.0), c(f32::NAN, 0.0), c(1.0, 1.0), c(0.0, 1.0)]).is_err());
    }
}
