//! The Bayes limit of a scene: the best forced-choice accuracy any classifier can reach from
//! `(ln F_max, ln t_c)` measured with Gaussian noise. Computed in f64, independently of the
//! kernel's f32 classifier (which approximates the same likelihood with the noise carried as
//! independent in `(ln R, ln u)`); here the noise keeps its correlation and the likelihood is
//! integrated numerically.
//!
//! A class maps `z = (x, y) = (ln R, ln u)` to `f = (ln F_max, ln t_c) = c + A z` with
//! `A = [[2, 6/5], [1, -1/5]]`, `|det A| = 8/5`. With `R` log-uniform and `p(u) ~ u^(beta-1)`,
//! the class density of `f` observed with noise `N(0, S)` is
//! `p(f) = (1 / |det A|) integral_box p(x) p(y) N(z; A^-1 (f - c), A^-1 S A^-T) dz`:
//! the `y` integral is closed (an exponential times a Gaussian), the `x` integral is
//! Gauss-Legendre over `mu_x +- 9 sigma_x` cut to the box.

/// `|det A|` of the map `(ln R, ln u) -> (ln F_max, ln t_c)`.
pub const JACOBIAN: f64 = 1.6;

/// One class in log feature space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClassModel {
    /// `ln c_F`, with `F_max = c_F R^2 u^(6/5)` (N, m, m/s).
    pub ln_force_coeff: f64,
    /// `ln c_t`, with `t_c = c_t R u^(-1/5)` (s, m, m/s).
    pub ln_duration_coeff: f64,
    /// `[ln R0, ln R1]` (R in m).
    pub ln_radius: (f64, f64),
    /// `[ln u0, ln u1]` (u in m/s).
    pub ln_speed: (f64, f64),
    /// Speed prior exponent: `p(ln u) ~ e^(beta ln u)` (1: uniform speed, 2: uniform height).
    pub speed_beta: f64,
    /// Prior weight of the class.
    pub prior: f64,
}

/// Gaussian measurement noise of `(ln F_max, ln t_c)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureNoise {
    /// Standard deviation of `ln F_max`.
    pub sigma_ln_force: f64,
    /// Standard deviation of `ln t_c`.
    pub sigma_ln_duration: f64,
    /// Correlation of the two, in `(-1, 1)`.
    pub correlation: f64,
}

/// A Monte Carlo estimate of a forced-choice accuracy.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Accuracy {
    /// Share of impacts classified right.
    pub accuracy: f64,
    /// Its standard error, `sqrt(a (1 - a) / n)`.
    pub std_error: f64,
    /// Impacts drawn.
    pub n: usize,
}

impl ClassModel {
    /// The class of a sphere material (`density_kg_m3`, effective modulus against the plate
    /// `effective_modulus_pa`) with radius in `radius_m` and speed in `speed_m_s`:
    /// `c_F = 4/3 E*^(2/5) (5 pi rho / 4)^(3/5)`, `c_t = 2.9432751843 (5 pi rho / (4 E*))^(2/5)`.
    pub fn new(
        effective_modulus_pa: f64,
        density_kg_m3: f64,
        radius_m: (f64, f64),
        speed_m_s: (f64, f64),
        speed_beta: f64,
        prior: f64,
    ) -> Self {
        let q = 5.0 * std::f64::consts::PI * density_kg_m3 / 4.0;
        Self {
            ln_force_coeff: (4.0 / 3.0 * effective_modulus_pa.powf(0.4) * q.powf(0.6)).ln(),
            ln_duration_coeff: (2.943_275_184_324_7 * (q / effective_modulus_pa).powf(0.4)).ln(),
            ln_radius: (radius_m.0.ln(), radius_m.1.ln()),
            ln_speed: (speed_m_s.0.ln(), speed_m_s.1.ln()),
            speed_beta,
            prior,
        }
    }

    /// `(ln F_max, ln t_c)` at `x = ln R`, `y = ln u`.
    pub fn forward(&self, x: f64, y: f64) -> (f64, f64) {
        (
            self.ln_force_coeff + 2.0 * x + 1.2 * y,
            self.ln_duration_coeff + x - 0.2 * y,
        )
    }

    /// `(ln R, ln u)` at `(ln F_max, ln t_c)`.
    pub fn invert(&self, ln_force: f64, ln_duration: f64) -> (f64, f64) {
        let a = ln_force - self.ln_force_coeff;
        let b = ln_duration - self.ln_duration_coeff;
        (0.125 * a + 0.75 * b, 0.625 * a - 1.25 * b)
    }

    /// A draw of `(ln R, ln u)` from the class's prior by inverse CDF from two uniforms in
    /// `(0, 1)`.
    pub fn sample(&self, u_radius: f64, u_speed: f64) -> (f64, f64) {
        let (x0, x1) = self.ln_radius;
        let (y0, y1) = self.ln_speed;
        let x = x0 + (x1 - x0) * u_radius;
        let b = self.speed_beta;
        let y = if b.abs() < 1e-12 {
            y0 + (y1 - y0) * u_speed
        } else {
            // CDF (e^(b y) - e^(b y0)) / (e^(b y1) - e^(b y0)).
            let (e0, e1) = ((b * y0).exp(), (b * y1).exp());
            (e0 + u_speed * (e1 - e0)).ln() / b
        };
        (x, y)
    }

    /// Prior density of `y = ln u` (0 outside the range).
    pub fn speed_density(&self, y: f64) -> f64 {
        let (y0, y1) = self.ln_speed;
        if y < y0 || y > y1 {
            return 0.0;
        }
        let b = self.speed_beta;
        if b.abs() < 1e-12 {
            1.0 / (y1 - y0)
        } else {
            b * (b * (y - y1)).exp() / (1.0 - (b * (y0 - y1)).exp())
        }
    }

    /// Noiseless density at `(ln F_max, ln t_c)`.
    pub fn density(&self, ln_force: f64, ln_duration: f64) -> f64 {
        let (x, y) = self.invert(ln_force, ln_duration);
        let (x0, x1) = self.ln_radius;
        if x < x0 || x > x1 {
            return 0.0;
        }
        self.speed_density(y) / (x1 - x0) / JACOBIAN
    }

    /// Density at `(ln F_max, ln t_c)` observed with `noise` (see the module docs).
    pub fn noisy_density(&self, ln_force: f64, ln_duration: f64, noise: &FeatureNoise) -> f64 {
        let (sf, st, r) = (
            noise.sigma_ln_force,
            noise.sigma_ln_duration,
            noise.correlation,
        );
        if sf <= 0.0 && st <= 0.0 {
            return self.density(ln_force, ln_duration);
        }
        // Covariance in z = A^-1 S A^-T with A^-1 = [[1/8, 3/4], [5/8, -5/4]].
        let (a, b, c, d) = (0.125, 0.75, 0.625, -1.25);
        let (sff, stt, sft) = (sf * sf, st * st, r * sf * st);
        let sxx = a * a * sff + 2.0 * a * b * sft + b * b * stt;
        let syy = c * c * sff + 2.0 * c * d * sft + d * d * stt;
        let sxy = a * c * sff + (a * d + b * c) * sft + b * d * stt;
        let (mx, my) = self.invert(ln_force, ln_duration);
        let sx = sxx.sqrt();
        // y given x: mean my + sxy/sxx (x - mx), variance syy - sxy^2/sxx.
        let cond_var = (syy - sxy * sxy / sxx).max(1e-30);
        let cond_s = cond_var.sqrt();
        let (x0, x1) = self.ln_radius;
        let lo = x0.max(mx - 9.0 * sx);
        let hi = x1.min(mx + 9.0 * sx);
        if lo >= hi {
            return 0.0;
        }
        let px = 1.0 / (x1 - x0);
        let (y0, y1) = self.ln_speed;
        let beta = self.speed_beta;
        let integral = gauss_legendre(lo, hi, |x| {
            let gx = normal_pdf((x - mx) / sx) / sx;
            let m = my + sxy / sxx * (x - mx);
            // integral_{y0}^{y1} p(y) N(y; m, s^2) dy, closed form.
            let py = if beta.abs() < 1e-12 {
                (phi((y1 - m) / cond_s) - phi((y0 - m) / cond_s)) / (y1 - y0)
            } else {
                let shift = beta * cond_var;
                let scale = beta / (1.0 - (beta * (y0 - y1)).exp());
                scale
                    * (beta * (m - y1) + 0.5 * beta * shift).exp()
                    * (phi((y1 - m - shift) / cond_s) - phi((y0 - m - shift) / cond_s))
            };
            gx * py
        });
        px * integral / JACOBIAN
    }
}

/// The scene's classes as [`ClassModel`]s (f64, from the scene file).
pub fn class_models(scene: &crate::scene::SceneFile) -> Vec<ClassModel> {
    let plate = scene.plate.material();
    scene
        .classes
        .iter()
        .map(|c| {
            let m = c.material.material();
            let u = c.speed_range_m_s();
            let beta = match c.speed {
                crate::scene::SpeedSpec::Uniform(_) => 1.0,
                crate::scene::SpeedSpec::DropHeight(_) => 2.0,
            };
            ClassModel::new(
                crate::physics::hertz64::effective_modulus_pa(&m, &plate),
                m.density_kg_m3,
                (c.radius_m.min, c.radius_m.max),
                (u.min, u.max),
                beta,
                c.prior,
            )
        })
        .collect()
}

/// The forced-choice (argmax posterior) class of an observation, from the exact noiseless
/// densities (`noise = None`) or the noisy ones.
pub fn decide(
    classes: &[ClassModel],
    ln_force: f64,
    ln_duration: f64,
    noise: Option<&FeatureNoise>,
) -> usize {
    let mut best = (0usize, f64::NEG_INFINITY);
    for (i, c) in classes.iter().enumerate() {
        let d = match noise {
            Some(n) => c.noisy_density(ln_force, ln_duration, n),
            None => c.density(ln_force, ln_duration),
        };
        let score = c.prior * d;
        if score > best.1 {
            best = (i, score);
        }
    }
    best.0
}

/// Bayes-limit accuracy by Monte Carlo: `n_per_class` impacts drawn from each class's prior,
/// observed with `noise` (none: the oracle on exact `(F_max, t_c)`), each decided by
/// [`decide`]; class results weighted by prior. `uniform` yields numbers in `(0, 1)`.
pub fn bayes_accuracy(
    classes: &[ClassModel],
    noise: Option<&FeatureNoise>,
    n_per_class: usize,
    uniform: &mut impl FnMut() -> f64,
) -> Accuracy {
    let total_prior: f64 = classes.iter().map(|c| c.prior).sum();
    let mut acc = 0.0;
    for (i, c) in classes.iter().enumerate() {
        let mut right = 0usize;
        for _ in 0..n_per_class {
            let (x, y) = c.sample(uniform(), uniform());
            let (mut lf, mut lt) = c.forward(x, y);
            if let Some(n) = noise {
                let (g1, g2) = gauss_pair(uniform);
                let r = n.correlation;
                lf += n.sigma_ln_force * g1;
                lt += n.sigma_ln_duration * (r * g1 + (1.0 - r * r).max(0.0).sqrt() * g2);
            }
            if decide(classes, lf, lt, noise) == i {
                right += 1;
            }
        }
        acc += c.prior / total_prior * right as f64 / n_per_class.max(1) as f64;
    }
    let n = n_per_class * classes.len();
    Accuracy {
        accuracy: acc,
        std_error: (acc * (1.0 - acc) / n.max(1) as f64).sqrt(),
        n,
    }
}

/// Two independent standard normals by Box-Muller.
pub(crate) fn gauss_pair(uniform: &mut impl FnMut() -> f64) -> (f64, f64) {
    let (a, b) = (uniform(), uniform());
    let r = (-2.0 * a.ln()).sqrt();
    let t = 2.0 * std::f64::consts::PI * b;
    (r * t.cos(), r * t.sin())
}

/// The standard normal distribution function, `Phi(x) = erfc(-x / sqrt 2) / 2`.
pub(crate) fn phi(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// The standard normal density, `exp(-x^2 / 2) / sqrt(2 pi)`.
pub(crate) fn normal_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// 32-point Gauss-Legendre quadrature of `f` over `[a, b]`.
pub(crate) fn gauss_legendre(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let (half, mid) = (0.5 * (b - a), 0.5 * (b + a));
    GL32.iter()
        .map(|&(x, w)| w * (f(mid + half * x) + f(mid - half * x)))
        .sum::<f64>()
        * half
}

/// Positive nodes and weights of the 32-point Gauss-Legendre rule on `[-1, 1]` (tabulated
/// digits kept as published).
#[allow(clippy::excessive_precision)]
const GL32: [(f64, f64); 16] = [
    (0.048_307_665_687_738_316, 0.096_540_088_514_727_8),
    (0.144_471_961_582_796_5, 0.095_638_720_079_274_86),
    (0.239_287_362_252_137_08, 0.093_844_399_080_804_57),
    (0.331_868_602_282_127_65, 0.091_173_878_695_763_88),
    (0.421_351_276_130_635_35, 0.087_652_093_004_403_81),
    (0.506_899_908_932_229_4, 0.083_311_924_226_946_76),
    (0.587_715_757_240_762_3, 0.078_193_895_787_070_3),
    (0.663_044_266_930_215_2, 0.072_345_794_108_848_51),
    (0.732_182_118_740_289_7, 0.065_822_222_776_361_85),
    (0.794_483_795_967_942_4, 0.058_684_093_478_535_55),
    (0.849_367_613_732_569_9, 0.050_998_059_262_376_18),
    (0.896_321_155_766_052_1, 0.042_835_898_022_226_68),
    (0.934_906_075_937_739_7, 0.034_273_862_913_021_43),
    (0.964_762_255_587_506_4, 0.025_392_065_309_262_06),
    (0.985_611_511_545_268_3, 0.016_274_394_730_905_67),
    (0.997_263_861_849_481_6, 0.007_018_610_009_470_097),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_weights_sum_to_two_and_integrate_polynomials() {
        let w: f64 = GL32.iter().map(|&(_, w)| 2.0 * w).sum();
        assert!((w - 2.0).abs() < 1e-14);
        // integral_0^1 x^20 dx = 1/21, exact for a 32-point rule.
        assert!((gauss_legendre(0.0, 1.0, |x| x.powi(20)) - 1.0 / 21.0).abs() < 1e-14);
    }

    #[test]
    fn noisy_density_integrates_to_one_and_tends_to_noiseless() {
        let c = ClassModel::new(6e9, 1380.0, (0.015, 0.04), (1.0, 5.0), 1.0, 1.0);
        let noise = FeatureNoise {
            sigma_ln_force: 0.05,
            sigma_ln_duration: 0.03,
            correlation: 0.3,
        };
        // 2-D midpoint integral over a box around the class in (ln F, ln t).
        let (mut lo_f, mut hi_f, mut lo_t, mut hi_t) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (x, y) in [
            (c.ln_radius.0, c.ln_speed.0),
            (c.ln_radius.1, c.ln_speed.0),
            (c.ln_radius.0, c.ln_speed.1),
            (c.ln_radius.1, c.ln_speed.1),
        ] {
            let (f, t) = c.forward(x, y);
            lo_f = lo_f.min(f - 0.5);
            hi_f = hi_f.max(f + 0.5);
            lo_t = lo_t.min(t - 0.5);
            hi_t = hi_t.max(t + 0.5);
        }
        let n = 400;
        let (df, dt) = ((hi_f - lo_f) / n as f64, (hi_t - lo_t) / n as f64);
        let mut total = 0.0;
        for i in 0..n {
            for j in 0..n {
                let f = lo_f + (i as f64 + 0.5) * df;
                let t = lo_t + (j as f64 + 0.5) * dt;
                total += c.noisy_density(f, t, &noise) * df * dt;
            }
        }
        assert!((total - 1.0).abs() < 2e-3, "{total}");
        // Far inside the class, tiny noise gives the noiseless density.
        let (f, t) = c.forward(-3.5, 1.0);
        let tiny = FeatureNoise {
            sigma_ln_force: 1e-4,
            sigma_ln_duration: 1e-4,
            correlation: 0.0,
        };
        let (a, b) = (c.noisy_density(f, t, &tiny), c.density(f, t));
        assert!((a / b - 1.0).abs() < 1e-6, "{a} {b}");
    }
}
