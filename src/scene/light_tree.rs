//! Many-light sampling: a bounding volume hierarchy over the emissive triangles (Conty Estevez
//! and Kulla 2018, "Importance Sampling of Many Lights"; pbrt-v4's `BVHLightSampler`). Each node
//! bounds its lights' points, their power and the cone of their normals; a shadow ray's light is
//! picked by walking from the root, at each node taking a child with probability proportional
//! to an upper bound of what it can send to the shading point (power × the best cosine at the
//! light × the best cosine at the receiver / squared distance). Near lights are chosen more
//! often than far ones of equal power, and lights behind the surface or facing away not at all.
//!
//! Reads the scene's emissive triangles and their power; writes nothing after the build. The
//! probability of any light at any point ([`LightTree::pmf`]) follows the same walk, so MIS
//! weighs light samples and BSDF samples with the density light sampling really had.

use crate::sampling::ONE_BELOW;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::f32::consts::PI;

/// How direct light picks the light of a shadow ray among the emissive triangles, the sun and the
/// environment (delta lights are each sampled once).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum LightSampler {
    /// By the light tree's bound of each light's contribution at the shading point (the default).
    #[default]
    Tree,
    /// By emitted power alone, the same at every point (for comparison).
    Power,
}

/// The share of the tree's light picks made by power instead ([`super::Scene::choose_light`]).
pub const DEFENSIVE_SHARE: f32 = 0.25;

/// A point that light is sampled for: its position, its shading normal on the side light is
/// wanted from, and whether it also takes light from behind (a surface that transmits).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Receiver {
    /// Position.
    pub p: Vec3,
    /// Unit shading normal on the incident side.
    pub n: Vec3,
    /// Takes light from both sides of `n`.
    pub two_sided: bool,
}

/// What the build knows of a set of lights: their points' box, total power, and the cone
/// around `axis` of half-angle acos(`cos_o`) holding their normals (every emitter here is
/// one-sided: it emits within 90° of its normal).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounds {
    lo: Vec3,
    hi: Vec3,
    power: f32,
    axis: Vec3,
    cos_o: f32,
}

/// cos(max(0, θa − θb)) from the sines and cosines of θa and θb.
#[inline]
fn cos_minus(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin(max(0, θa − θb)).
#[inline]
fn sin_minus(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

#[inline]
fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

impl Bounds {
    fn union(&self, o: &Bounds) -> Bounds {
        let (axis, cos_o) = cone_union((self.axis, self.cos_o), (o.axis, o.cos_o));
        Bounds { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi), power: self.power + o.power, axis, cos_o }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// The orientation measure M_Ω of Conty Estevez and Kulla: the solid angle the cone's
    /// normals light, cosine-weighted (2π(1 − cos θo) + π/2·(2θw sin θo − cos(θo − 2θw) −
    /// 2θo sin θo + cos θo) with θw = min(θo + π/2, π)).
    fn orientation_measure(&self) -> f32 {
        let theta_o = self.cos_o.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + PI / 2.0).min(PI);
        let sin_o = theta_o.sin();
        2.0 * PI * (1.0 - self.cos_o)
            + PI / 2.0 * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + self.cos_o)
    }
}

/// The smallest cone holding two cones of directions (axis, cosine of the half-angle).
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let (theta_a, theta_b) = (a.1.clamp(-1.0, 1.0).acos(), b.1.clamp(-1.0, 1.0).acos());
    let theta_d = a.0.dot(b.0).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (a.0, -1.0);
    }
    // Turn a's axis toward b's by θo − θa.
    let turn = a.0.cross(b.0);
    if turn.length_squared() < 1e-12 {
        return (a.0, -1.0);
    }
    let axis = glam::Quat::from_axis_angle(turn.normalize(), theta_o - theta_a) * a.0;
    (axis.normalize(), theta_o.cos())
}

/// A node as the walk reads it: its lights' bounding sphere (the box's centre and half
/// diagonal), power / π, normals' cone, and either one light or the index of its second child
/// (the first follows it).
#[derive(Clone, Copy, Debug)]
struct Node {
    centre: Vec3,
    radius2: f32,
    power: f32,
    axis: Vec3,
    cos_o: f32,
    sin_o: f32,
    /// Index in the scene's `lights` for a leaf; the second child's node index otherwise.
    index: u32,
    /// A point of a leaf's triangle (its first vertex), which with `axis` gives its plane;
    /// `None` for an inner node.
    leaf: Option<Vec3>,
}

impl Node {
    fn new(b: &Bounds, index: u32, leaf: Option<Vec3>) -> Node {
        Node {
            centre: b.centroid(),
            radius2: 0.25 * (b.hi - b.lo).length_squared(),
            power: b.power / PI,
            axis: b.axis,
            cos_o: b.cos_o,
            sin_o: sin_of(b.cos_o),
            index,
            leaf,
        }
    }

    /// An upper bound of the irradiance the node's lights put on `r`: power/π × the cosine at
    /// the light of the smallest angle between a normal of the cone and a direction toward `r`
    /// from the bounding sphere × the like cosine at the receiver / the squared distance to the
    /// centre (at least the radius², so that a receiver inside it is not a division by zero) —
    /// the irradiance of a small far emitter, cos·cos·A·L/d². Zero where every light faces away
    /// from `r` or lies below its surface; for a leaf, where `r` lies behind its triangle's
    /// emitting face.
    #[inline]
    fn importance(&self, r: &Receiver) -> f32 {
        let to_r = r.p - self.centre;
        let d2 = to_r.length_squared();
        // The bounding sphere as seen from r: a cone of half-angle θb around its centre.
        let inside = d2 <= self.radius2;
        let (sin_b, cos_b) = if inside {
            (1.0, -1.0)
        } else {
            let sin2 = self.radius2 / d2;
            (sin2.sqrt(), (1.0 - sin2).sqrt())
        };
        let inv_d = if d2 > 0.0 { d2.sqrt().recip() } else { 0.0 };
        // At the lights: the angle from the normals' cone to r, less the sphere's spread.
        let cos_w = if inside { 1.0 } else { self.axis.dot(to_r) * inv_d };
        let sin_w = sin_of(cos_w);
        // Lights of one normal (a leaf, a flat emitter's triangles): θx = θw.
        let (cos_x, sin_x) = if self.sin_o == 0.0 {
            (cos_w, sin_w)
        } else {
            (cos_minus(sin_w, cos_w, self.sin_o, self.cos_o), sin_minus(sin_w, cos_w, self.sin_o, self.cos_o))
        };
        let cos_light = cos_minus(sin_x, cos_x, sin_b, cos_b);
        // One-sided emitters send nothing beyond 90° of their normal.
        if !(cos_light > 0.0) {
            return 0.0;
        }
        // At the receiver: the angle from its normal to the sphere's centre, less its spread.
        let cos_i = if inside { 1.0 } else { -to_r.dot(r.n) * inv_d };
        let cos_i = if r.two_sided { cos_i.abs() } else { cos_i };
        let cos_recv = cos_minus(sin_of(cos_i), cos_i, sin_b, cos_b);
        if !(cos_recv > 0.0) {
            return 0.0;
        }
        // A leaf's triangle has one plane: the cosine at any of its points toward r is at most
        // h / (distance from r to the triangle) ≥ h / (d − radius), h the height of r above the
        // plane — next to nothing for a neighbour almost in the receiver's plane (a triangle of
        // the wall a receiver lies on), which the cone and sphere cannot tell from a facing one.
        let cos_light = match self.leaf {
            Some(v0) => {
                let h = (r.p - v0).dot(self.axis);
                if !(h > 0.0) {
                    return 0.0;
                }
                let gap = if inside { 0.0 } else { d2.sqrt() - self.radius2.sqrt() };
                if h < gap {
                    cos_light.min(h / gap)
                } else {
                    cos_light
                }
            }
            None => cos_light,
        };
        let v = self.power * cos_light * cos_recv / d2.max(self.radius2);
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }
}

/// Whether triangle `v` is near `p`: closer than 5 times its bounding radius about its
/// centroid. Near, the 1/d² of area sampling varies more than 2.25× over it, and it is sampled
/// by solid angle ([`crate::scene::light::area_light_sampling`]) and weighed by solid angle in
/// the light tree; far, by area and by the tree's bound. One rule for both, in f32, with no
/// square root: a far triangle never computes its solid angle.
#[must_use]
#[inline]
pub fn near(v: &[Vec3; 3], p: Vec3) -> bool {
    let c = (v[0] + v[1] + v[2]) / 3.0;
    let r2 = (v[0] - c).length_squared().max((v[1] - c).length_squared()).max((v[2] - c).length_squared());
    (p - c).length_squared() < 25.0 * r2
}

/// Buckets per axis of the build's split search.
const BUCKETS: usize = 12;

/// Depth from which the build splits in the middle of its list, which bounds the tree's depth by
/// this plus log₂ of the light count (each light's path is kept in 128 bits).
const BALANCED_FROM: u32 = 80;

/// The light tree over a scene's emissive triangles.
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Per light of the scene (index in `lights`; `None` for lights not in the tree): its path
    /// from the root, bit d set where it goes to the second child at depth d.
    paths: Vec<Option<u128>>,
}

/// One light for the build: its index in the scene's lights and its bounds.
#[derive(Clone, Copy, Debug)]
pub struct TreeLight {
    /// Index in the scene's `lights`.
    pub light: u32,
    /// Vertices of its triangle.
    pub p: [Vec3; 3],
    /// Unit normal of its emitting face.
    pub n: Vec3,
    /// Emitted power (mean over channels).
    pub power: f32,
}

impl LightTree {
    /// The tree over `lights` of a scene with `light_count` lights in all; `None` without any
    /// light of positive power.
    #[must_use]
    pub fn build(lights: &[TreeLight], light_count: usize) -> Option<LightTree> {
        let mut items: Vec<(u32, Bounds)> = lights
            .iter()
            .filter(|l| l.power > 0.0 && l.power.is_finite())
            .map(|l| {
                let lo = l.p[0].min(l.p[1]).min(l.p[2]);
                let hi = l.p[0].max(l.p[1]).max(l.p[2]);
                (l.light, Bounds { lo, hi, power: l.power, axis: l.n, cos_o: 1.0 })
            })
            .collect();
        if items.is_empty() {
            return None;
        }
        let mut corners = vec![Vec3::ZERO; light_count];
        for l in lights {
            corners[l.light as usize] = l.p[0];
        }
        let mut tree = LightTree { nodes: Vec::with_capacity(2 * items.len()), paths: vec![None; light_count] };
        tree.build_node(&mut items, &corners, 0, 0);
        Some(tree)
    }

    fn build_node(&mut self, items: &mut [(u32, Bounds)], corners: &[Vec3], depth: u32, path: u128) -> Bounds {
        let bounds = items[1..].iter().fold(items[0].1, |b, i| b.union(&i.1));
        let at = self.nodes.len();
        if items.len() == 1 {
            self.nodes.push(Node::new(&bounds, items[0].0, Some(corners[items[0].0 as usize])));
            self.paths[items[0].0 as usize] = Some(path);
            return bounds;
        }
        self.nodes.push(Node::new(&bounds, 0, None));
        let mid = if depth >= BALANCED_FROM { items.len() / 2 } else { split(items, &bounds) };
        let (first, second) = items.split_at_mut(mid);
        self.build_node(first, corners, depth + 1, path);
        self.nodes[at].index = self.nodes.len() as u32;
        self.build_node(second, corners, depth + 1, path | (1u128 << depth));
        bounds
    }

    /// Picks a light for `r` with uniform `u`: its index in the scene's lights and its
    /// probability. `None` where no light of the tree can reach `r`.
    #[must_use]
    pub fn sample(&self, r: &Receiver, mut u: f32) -> Option<(u32, f32)> {
        // The root's own importance is not asked: where it is zero, so are its children's.
        let (mut at, mut pmf) = (0usize, 1.0f32);
        loop {
            let node = &self.nodes[at];
            if node.leaf.is_some() {
                return Some((node.index, pmf));
            }
            let (first, second) = (at + 1, node.index as usize);
            let (i0, i1) = (self.nodes[first].importance(r), self.nodes[second].importance(r));
            let p0 = i0 / (i0 + i1);
            if !(p0 >= 0.0) {
                return None;
            }
            if u < p0 {
                at = first;
                pmf *= p0;
                u = (u / p0).min(ONE_BELOW);
            } else {
                at = second;
                pmf *= 1.0 - p0;
                u = ((u - p0) / (1.0 - p0)).clamp(0.0, ONE_BELOW);
            }
        }
    }

    /// The probability that [`LightTree::sample`] picks light `light` (index in the scene's
    /// lights) for `r`; 0 for a light not in the tree or out of reach.
    #[must_use]
    pub fn pmf(&self, r: &Receiver, light: u32) -> f32 {
        let Some(Some(path)) = self.paths.get(light as usize) else { return 0.0 };
        let (mut at, mut pmf, mut depth) = (0usize, 1.0f32, 0);
        while self.nodes[at].leaf.is_none() {
            let (first, second) = (at + 1, self.nodes[at].index as usize);
            let (i0, i1) = (self.nodes[first].importance(r), self.nodes[second].importance(r));
            let p0 = i0 / (i0 + i1);
            if !(p0 >= 0.0) {
                return 0.0;
            }
            if path >> depth & 1 == 0 {
                at = first;
                pmf *= p0;
            } else {
                at = second;
                pmf *= 1.0 - p0;
            }
            depth += 1;
        }
        pmf
    }

    /// Nodes in the tree.
    #[must_use]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tree has no node (never: an empty tree is not built).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// Orders `items` and returns where to split them: the bucket boundary of least cost (power ×
/// orientation measure × surface area of each side, Conty Estevez and Kulla's SAOH, the axis's
/// cost scaled by how thin the box is along it) over the three axes of the centroids' box; the
/// middle of the list where the centroids coincide.
fn split(items: &mut [(u32, Bounds)], bounds: &Bounds) -> usize {
    let centroids = items.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), i| {
        let c = i.1.centroid();
        (lo.min(c), hi.max(c))
    });
    let extent = centroids.1 - centroids.0;
    let diagonal = bounds.hi - bounds.lo;
    let mut best: Option<(f32, usize, f32)> = None;
    for axis in 0..3 {
        if !(extent[axis] > 0.0) {
            continue;
        }
        let bucket = |b: &Bounds| {
            let t = (b.centroid()[axis] - centroids.0[axis]) / extent[axis];
            ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
        };
        let mut buckets: [Option<Bounds>; BUCKETS] = [None; BUCKETS];
        for (_, b) in items.iter() {
            let k = bucket(b);
            buckets[k] = Some(buckets[k].map_or(*b, |x| x.union(b)));
        }
        let cost = |b: Option<Bounds>| {
            b.map_or(0.0, |b| {
                let d = b.hi - b.lo;
                b.power * b.orientation_measure() * 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
            })
        };
        let thinness = diagonal.max_element() / diagonal[axis].max(f32::MIN_POSITIVE);
        for cut in 1..BUCKETS {
            let fold = |s: &[Option<Bounds>]| {
                s.iter().flatten().fold(None, |acc: Option<Bounds>, b| Some(acc.map_or(*b, |a| a.union(b))))
            };
            let (below, above) = (fold(&buckets[..cut]), fold(&buckets[cut..]));
            if below.is_none() || above.is_none() {
                continue;
            }
            let c = thinness * (cost(below) + cost(above));
            if best.is_none_or(|b| c < b.0) {
                best = Some((c, axis, centroids.0[axis] + extent[axis] * cut as f32 / BUCKETS as f32));
            }
        }
    }
    let Some((_, axis, at)) = best else { return items.len() / 2 };
    let mid = partition(items, |b| b.centroid()[axis] < at);
    if mid == 0 || mid == items.len() {
        items.len() / 2
    } else {
        mid
    }
}

/// Moves the items whose bounds satisfy `below` to the front, keeping each side's order
/// (a stable partition: the tree does not depend on the sort's internals); returns their count.
fn partition(items: &mut [(u32, Bounds)], below: impl Fn(&Bounds) -> bool) -> usize {
    let (mut front, back): (Vec<_>, Vec<_>) = items.iter().partition(|i| below(&i.1));
    let n = front.len();
    front.extend(back);
    items.copy_from_slice(&front);
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 200 small triangles facing down from a ceiling at y = 2 over x, z in [-5, 5], of powers
    /// from 1 to 100, with a few facing up (which nothing below can see).
    fn ceiling() -> Vec<TreeLight> {
        (0..200u32)
            .map(|i| {
                let h = |k: u32| (i.wrapping_mul(2_654_435_761u32.wrapping_add(k * 40_503)) % 10_007) as f32 / 10_007.0;
                let c = Vec3::new(10.0 * h(1) - 5.0, 2.0, 10.0 * h(2) - 5.0);
                let up = i % 17 == 0;
                let (a, b) = (Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.1));
                let p = if up { [c, c + b, c + a] } else { [c, c + a, c + b] };
                let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
                TreeLight { light: i, p, n, power: 1.0 + 99.0 * h(3) }
            })
            .collect()
    }

    fn floor_receivers() -> Vec<Receiver> {
        (0..25)
            .map(|i| Receiver {
                p: Vec3::new((i % 5) as f32 * 2.0 - 4.0, 0.0, (i / 5) as f32 * 2.0 - 4.0),
                n: Vec3::Y,
                two_sided: false,
            })
            .collect()
    }

    #[test]
    fn every_pick_has_the_probability_its_walk_gives_and_they_sum_to_one() {
        let lights = ceiling();
        let tree = LightTree::build(&lights, lights.len()).expect("a tree");
        for r in floor_receivers() {
            for i in 0..256 {
                let u = (i as f32 + 0.5) / 256.0;
                let (light, pmf) = tree.sample(&r, u).expect("a light reaches the floor");
                assert_eq!(pmf, tree.pmf(&r, light), "light {light} at {:?}", r.p);
                assert!(light % 17 != 0, "light {light} faces away from the floor");
            }
            let sum: f32 = (0..lights.len() as u32).map(|l| tree.pmf(&r, l)).sum();
            assert!((sum - 1.0).abs() < 1e-5, "at {:?}: the probabilities sum to {sum}", r.p);
            for l in (0..lights.len() as u32).filter(|l| l % 17 == 0) {
                assert_eq!(tree.pmf(&r, l), 0.0);
            }
        }
    }

    #[test]
    fn near_lights_are_picked_more_often_than_far_ones_of_equal_power() {
        // Two equal lights 1 and 9 units from the receiver: the tree's bound is 1/d², so the
        // near one takes at least 80 of every 82 picks (the bound's ratio is 81).
        let tri = |x: f32| {
            let c = Vec3::new(x, 1.0, 0.0);
            [c, c + Vec3::new(0.01, 0.0, 0.0), c + Vec3::new(0.0, 0.0, 0.01)]
        };
        let lights: Vec<TreeLight> = [0.0, 9.0]
            .iter()
            .enumerate()
            .map(|(i, &x)| TreeLight { light: i as u32, p: tri(x), n: Vec3::NEG_Y, power: 1.0 })
            .collect();
        let tree = LightTree::build(&lights, 2).unwrap();
        let r = Receiver { p: Vec3::ZERO, n: Vec3::Y, two_sided: false };
        assert!(tree.pmf(&r, 0) > 80.0 / 82.0, "{}", tree.pmf(&r, 0));
        assert!((tree.pmf(&r, 0) + tree.pmf(&r, 1) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_light_behind_the_receiver_or_facing_away_is_never_picked() {
        // A faces down over the origin; B, 3 units aside at the same height, faces up.
        let square = |c: Vec3, n: Vec3| {
            let p = [c, c + Vec3::new(0.1, 0.0, 0.0), c + Vec3::new(0.0, 0.0, 0.1)];
            if n.y < 0.0 {
                p
            } else {
                [p[0], p[2], p[1]]
            }
        };
        let lights = [
            TreeLight { light: 0, p: square(Vec3::Y, Vec3::NEG_Y), n: Vec3::NEG_Y, power: 1.0 },
            TreeLight { light: 1, p: square(Vec3::new(3.0, 1.0, 0.0), Vec3::Y), n: Vec3::Y, power: 1.0 },
        ];
        let tree = LightTree::build(&lights, 2).unwrap();
        let below = Receiver { p: Vec3::ZERO, n: Vec3::NEG_Y, two_sided: false };
        assert_eq!((tree.pmf(&below, 0), tree.pmf(&below, 1)), (0.0, 0.0), "the receiver faces away from both");
        assert!(tree.sample(&below, 0.5).is_none());
        let two_sided = Receiver { two_sided: true, ..below };
        assert_eq!(tree.pmf(&two_sided, 0), 1.0, "a transmitting receiver takes A from behind; B faces away");
        let above = Receiver { p: Vec3::new(0.0, 2.0, 0.0), n: Vec3::NEG_Y, two_sided: false };
        assert_eq!(tree.pmf(&above, 0), 0.0, "behind A's emitting face");
        assert_eq!(tree.pmf(&above, 1), 1.0);
    }

    #[test]
    fn coinciding_lights_still_build_a_tree_of_bounded_depth() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Z];
        let lights: Vec<TreeLight> = (0..1000).map(|i| TreeLight { light: i, p, n: Vec3::NEG_Y, power: 1.0 }).collect();
        let tree = LightTree::build(&lights, 1000).unwrap();
        assert_eq!(tree.len(), 1999);
        let r = Receiver { p: Vec3::new(0.2, -1.0, 0.2), n: Vec3::Y, two_sided: false };
        let sum: f32 = (0..1000).map(|l| tree.pmf(&r, l)).sum();
        assert!((sum - 1.0).abs() < 1e-4, "{sum}");
    }
}
