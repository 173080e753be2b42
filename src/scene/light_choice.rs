//! Which light a shadow ray samples: the scene's pick among the emissive triangles, suns and
//! the environment for a receiver (a shading point and its normal), by the light tree with a
//! defensive share of power's picks, or by power alone, and the probability of any light under
//! either — the density MIS weighs BSDF samples against. Reads the scene's light tables and tree;
//! writes nothing.

use super::light::Light;
use super::light_tree::{LightSampler, LightTree, Receiver, DEFENSIVE_SHARE};
use super::Scene;
use crate::sampling::ONE_BELOW;

impl Scene {
    /// Picks the light of a shadow ray toward receiver `r` with uniform `u`, among the lights
    /// sampled `light_samples` times (emissive triangles, suns, the environment): its index in
    /// `lights` and its probability. `how` says how ([`LightSampler`]). The tree's pick is a
    /// defensive mixture (Hesterberg 1995): with probability [`DEFENSIVE_SHARE`] by power, else
    /// by the tree, and the probability is the mixture's, so no light's is ever below that share
    /// of its power's — where the tree's bound misjudges (an object inside an emitting sphere,
    /// which power alone samples exactly) the noise stays within a factor of power's. Without a
    /// tree (no emissive triangle), power decides. `None` where the pick reaches no light.
    #[must_use]
    pub fn choose_light(&self, how: LightSampler, r: &Receiver, u: f32) -> Option<(u32, f32)> {
        let power = self.area_power.as_ref()?;
        let Some((tree, share)) = self.light_tree.as_ref().filter(|_| how == LightSampler::Tree) else {
            let k = power.sample(u);
            return Some((self.area_lights[k], power.pmf(k) as f32));
        };
        let d = DEFENSIVE_SHARE;
        let (light, by_tree) = if u < d {
            let k = power.sample(u / d);
            (self.area_lights[k], self.tree_side_pmf(tree, *share, r, self.area_lights[k]))
        } else {
            // The tree with the emitters' share of the power, else a sun or the environment.
            let (u, share) = (((u - d) / (1.0 - d)).min(ONE_BELOW), *share as f32);
            match &self.infinite_power {
                Some((lights, dist)) if u >= share => {
                    let k = dist.sample(((u - share) / (1.0 - share)).clamp(0.0, ONE_BELOW));
                    (lights[k], dist.pmf(k) as f32 * (1.0 - share))
                }
                _ => {
                    let (light, pmf) = tree.sample(r, (u / share).min(ONE_BELOW))?;
                    (light, pmf * share)
                }
            }
        };
        let pmf = d * self.power_pmf(light) + (1.0 - d) * by_tree;
        (pmf > 0.0).then_some((light, pmf))
    }

    /// The probability that [`Scene::choose_light`] picks light `light` (index in `lights`)
    /// for `r`: MIS's light-sampling density.
    #[must_use]
    pub fn light_pmf(&self, how: LightSampler, r: &Receiver, light: u32) -> f32 {
        match self.light_tree.as_ref().filter(|_| how == LightSampler::Tree) {
            Some((tree, share)) => {
                DEFENSIVE_SHARE * self.power_pmf(light)
                    + (1.0 - DEFENSIVE_SHARE) * self.tree_side_pmf(tree, *share, r, light)
            }
            None => self.power_pmf(light),
        }
    }

    /// The probability of `light` when picked by power among `area_lights`.
    fn power_pmf(&self, light: u32) -> f32 {
        let Some(power) = &self.area_power else { return 0.0 };
        // Emissive triangles come first in both lists, at the same index.
        let k = light as usize;
        if self.area_lights.get(k) == Some(&light) {
            return power.pmf(k) as f32;
        }
        self.area_lights.binary_search(&light).map_or(0.0, |k| power.pmf(k) as f32)
    }

    /// The probability of `light` when the tree's side of [`Scene::choose_light`] picks it: the
    /// tree's for an emitter, times the emitters' `share` of the power; by power among the suns
    /// and the environment for the rest.
    fn tree_side_pmf(&self, tree: &LightTree, share: f64, r: &Receiver, light: u32) -> f32 {
        if matches!(self.lights[light as usize], Light::Area { .. }) {
            return tree.pmf(r, light) * share as f32;
        }
        let Some((lights, dist)) = &self.infinite_power else { return 0.0 };
        lights.binary_search(&light).map_or(0.0, |k| dist.pmf(k) as f32 * (1.0 - share as f32))
    }
}
