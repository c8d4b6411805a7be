//! The noiseless Bayes limit of a scene whose classes may yield: the best forced-choice
//! accuracy from the exact `(ln F_max, ln t_c)` when each class maps `(ln R, ln u)` through
//! Thornton's closed forms ([`crate::physics::thornton`]) instead of the Hertz power laws.
//!
//! The map is no longer linear, so the class density of an observation `f` is found by
//! inverting it per class: Newton's method on `g(x, y) = f` (`x = ln R`, `y = ln u`,
//! Jacobian `J` by central differences), then `p(f) = p(x) p(y) / |det J|` when the pre-image
//! lies in the class's box, 0 otherwise. The prior density `p(x) p(y)` is the Hertz
//! [`ClassModel`]'s (the same priors), read through its own linear map. Only undamped contacts
//! have closed forms; a scene with a restitution-law damping is refused.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::physics::hertz64::{HertzImpact64, Material64};
use crate::physics::law_spec::LawSpec;
use crate::physics::sim_error::SimError;
use crate::physics::thornton::ThorntonImpact64;
use crate::scene::SceneFile;
use crate::score::bayes::{Accuracy, ClassModel};
use crate::score::evaluate::class_models;

/// Half-width of the central differences of the Jacobian, in log units.
const DIFF_STEP: f64 = 1e-6;

/// Newton iterations at most per inversion.
const MAX_NEWTON: usize = 60;

/// One class: its map `(ln R, ln u) -> (ln F_max, ln t_c)` and its priors.
#[derive(Debug, Clone, Copy)]
pub struct YieldClass {
    /// Sphere material.
    pub sphere: Material64,
    /// Plate material.
    pub plate: Material64,
    /// Limiting contact pressure in Pa, or `None` (elastic: Hertz).
    pub yield_pressure_pa: Option<f64>,
    /// The class's priors (and its Hertz map, used only to read the prior density).
    pub prior: ClassModel,
}

impl YieldClass {
    /// `(ln F_max, ln t_c)` at `x = ln R`, `y = ln u` from the closed forms.
    pub fn forward(&self, x: f64, y: f64) -> Result<(f64, f64), SimError> {
        let h = HertzImpact64::new(&self.sphere, &self.plate, x.exp(), y.exp())?;
        Ok(match self.yield_pressure_pa {
            Some(p_y) => {
                let t = ThorntonImpact64::new(&h, p_y)?;
                (t.peak_force_n.ln(), t.duration_s.ln())
            }
            None => (h.peak_force_n.ln(), h.duration_s.ln()),
        })
    }

    /// Jacobian `d(ln F, ln t) / d(x, y)` at `(x, y)` by central differences.
    fn jacobian(&self, x: f64, y: f64) -> Result<[[f64; 2]; 2], SimError> {
        let h = DIFF_STEP;
        let (fxp, fxm) = (self.forward(x + h, y)?, self.forward(x - h, y)?);
        let (fyp, fym) = (self.forward(x, y + h)?, self.forward(x, y - h)?);
        Ok([
            [(fxp.0 - fxm.0) / (2.0 * h), (fyp.0 - fym.0) / (2.0 * h)],
            [(fxp.1 - fxm.1) / (2.0 * h), (fyp.1 - fym.1) / (2.0 * h)],
        ])
    }

    /// The pre-image `(x, y)` of `f` and `|det J|` there, or `None` if Newton does not converge
    /// to `1e-12` in log units.
    pub fn invert(&self, f: (f64, f64)) -> Option<(f64, f64, f64)> {
        let (mut x, mut y) = (
            0.5 * (self.prior.ln_radius.0 + self.prior.ln_radius.1),
            0.5 * (self.prior.ln_speed.0 + self.prior.ln_speed.1),
        );
        for _ in 0..MAX_NEWTON {
            let g = self.forward(x, y).ok()?;
            let (r0, r1) = (g.0 - f.0, g.1 - f.1);
            let j = self.jacobian(x, y).ok()?;
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if r0.abs().max(r1.abs()) < 1e-12 {
                return Some((x, y, det.abs()));
            }
            if !(det.is_finite() && det != 0.0) {
                return None;
            }
            let dx = (j[1][1] * r0 - j[0][1] * r1) / det;
            let dy = (j[0][0] * r1 - j[1][0] * r0) / det;
            // At most one log unit per step, so that a far start does not overshoot.
            let scale = 1.0 / dx.abs().max(dy.abs()).max(1.0);
            x -= scale * dx;
            y -= scale * dy;
        }
        None
    }

    /// Noiseless density of the class at `f = (ln F_max, ln t_c)` (0 outside its image, or
    /// where the inversion fails).
    pub fn density(&self, f: (f64, f64)) -> f64 {
        let Some((x, y, det)) = self.invert(f) else {
            return 0.0;
        };
        // p(x) p(y) from the Hertz model's own density at its image of (x, y).
        let (hf, ht) = self.prior.forward(x, y);
        self.prior.density(hf, ht) * crate::score::bayes::JACOBIAN / det
    }
}

/// The scene's classes with their yield pressures. Errors if a yielding class's law is damped
/// (no closed form).
pub fn yield_classes(scene: &SceneFile) -> Result<Vec<YieldClass>, SimError> {
    let plate = scene.plate.material();
    let priors = class_models(scene);
    let mut out = Vec::new();
    for (i, (c, prior)) in scene.classes.iter().zip(priors).enumerate() {
        if let LawSpec::Thornton {
            damping: Some(_), ..
        } = scene.class_law(i)?
        {
            return Err(SimError::InvalidParameter {
                name: "contact.law".to_string(),
                value: f64::NAN,
                requirement: "hertz for the yielding Bayes limit (a damped contact has no \
                              closed form)",
            });
        }
        out.push(YieldClass {
            sphere: c.material.material(),
            plate,
            yield_pressure_pa: c.yield_pressure_pa,
            prior,
        });
    }
    Ok(out)
}

/// The argmax of `prior * density` over `classes` at `f`.
pub fn decide(classes: &[YieldClass], f: (f64, f64)) -> usize {
    let total: f64 = classes.iter().map(|c| c.prior.prior).sum();
    let mut best = (0, f64::NEG_INFINITY);
    for (i, c) in classes.iter().enumerate() {
        let score = c.prior.prior / total * c.density(f);
        if score > best.1 {
            best = (i, score);
        }
    }
    best.0
}

/// The noiseless Bayes limit by Monte Carlo: `n_per_class` draws per class from its prior
/// (ChaCha8 seeded with `seed`), each decided by [`decide`] on its exact features; classes
/// weighted by their priors.
pub fn yield_bayes_accuracy(
    classes: &[YieldClass],
    n_per_class: usize,
    seed: u64,
) -> Result<Accuracy, SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let total: f64 = classes.iter().map(|c| c.prior.prior).sum();
    let mut acc = 0.0;
    for (i, c) in classes.iter().enumerate() {
        let mut right = 0usize;
        for _ in 0..n_per_class {
            let (x, y) = c.prior.sample(rng.random(), rng.random());
            if decide(classes, c.forward(x, y)?) == i {
                right += 1;
            }
        }
        acc += c.prior.prior / total * right as f64 / n_per_class.max(1) as f64;
    }
    let n = n_per_class * classes.len();
    Ok(Accuracy {
        accuracy: acc,
        std_error: (acc * (1.0 - acc) / n.max(1) as f64).sqrt(),
        n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without yield the numerical inversion reproduces the Hertz model's exact linear one: the
    /// densities agree to 1e-6 inside the image, and the decisions on draws agree.
    #[test]
    fn elastic_classes_match_the_linear_hertz_model() {
        let scene = SceneFile::paper();
        let classes = yield_classes(&scene).expect("undamped");
        let models = class_models(&scene);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut agree = 0;
        for k in 0..400 {
            let c = &classes[k % 2];
            let (x, y) = c.prior.sample(rng.random(), rng.random());
            let f = c.forward(x, y).expect("forward");
            for (yc, m) in classes.iter().zip(&models) {
                let (a, b) = (yc.density(f), m.density(f.0, f.1));
                assert!((a - b).abs() <= 1e-6 * b.max(1e-300) || (a == 0.0 && b == 0.0));
            }
            agree += usize::from(
                decide(&classes, f) == crate::score::bayes::decide(&models, f.0, f.1, None),
            );
        }
        assert_eq!(agree, 400);
    }
}
