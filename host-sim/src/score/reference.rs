//! The reference limit of a scene: the best forced-choice accuracy any classifier can reach
//! from the features `f = (ln F_max, ln t_c)` of the scene's impacts measured in the scene's
//! stated sensor noise, computed from physics alone (no figure of the kernel enters).
//!
//! # Method
//!
//! 1. **Noiseless features.** For every class, a grid of `grid x grid` impacts spans its
//!    prior box in `z = (x, y) = (ln R, ln u)`. Each is integrated with the scene's contact
//!    law (a class that states a yield pressure: Thornton's law, [`SceneFile::class_law`]) by
//!    host-sim's integrator ([`crate::physics::impact::simulate`]): `F_max` is the peak force,
//!    and `t_c` is read two ways ([`DurationFeature`]): the pulse's duration (first contact to
//!    the first zero of the force after its peak, as the stream's truth defines it), or the
//!    duration its impulse gives, `J / (C_AREA F_max)` (`J = integral F dt`; the two agree
//!    for Hertz). For a pulse whose shape changes over the box (a damped or yielding law)
//!    each pair holds information the other lacks; the reference is the larger of the two
//!    limits (step 5), since each bounds what an estimator of that pair can reach, and an
//!    estimator may use either. For undamped Hertz the features are the
//!    closed forms `F_max = k delta_max^(3/2)`, `t_c = 2.9432751843 delta_max / u`. Damped
//!    laws, and the Adams law with a fixed `c_max` (whose damping ratio changes with size and
//!    speed), need no calibration: the integrator gives their features directly.
//! 2. **Measurement noise.** At each grid impact the Cramér-Rao bound of `f` for the sampled
//!    pulse through the scene's chain in the scene's noise ([`crate::score::crb`]), with the
//!    onset known within the bracket its first sample above the noise sets (the samples'
//!    support), averaged over the onset's phase within a sample: the covariance `S(z)` no unbiased estimator beats.
//! 3. **Interpolation.** Between grid points the deviation `d(z) = f(z) - (c + A z)` from the
//!    Hertz power laws (`A = [[2, 6/5], [1, -1/5]]`, zero for Hertz, a constant for the
//!    restitution-parametrised laws), `ln sigma` of both features and their correlation are
//!    bilinear in `z` (clamped at the box's edges).
//! 4. **Class densities.** `p(f | c) = integral_box p_c(z) N(f; g(z), S(z)) dz` with
//!    `g(z) = c + A z + d(z)`. It is evaluated by linearising `g` about the preimage
//!    `z* = g^-1(f)` (Newton) and taking `S` there: `p(f | c) = integral_box p_c(z)
//!    N(z; z*, J^-1 S J^-T) dz / |det J|`, `J` the Jacobian of `g` at `z*`; the `y` integral
//!    by Gauss-Legendre over `y* +- 8 sigma_y` cut to the box, the `x` integral (`x` uniform)
//!    in closed form given `y`. Without noise, `p(f | c) = p_c(z*) / |det J|`.
//! 5. **Accuracy.** Monte Carlo over fresh draws of each class's prior: the exact features
//!    `g(z)` plus Gaussian noise of covariance `S(z)`, decided by the largest
//!    `prior_c p(f | c)`; class results weighted by the normalised priors, with the standard
//!    error `sqrt(a (1 - a) / n)`. Each draw counts with the probability that its pulse is
//!    found at all, `Phi(d - eta)`: `d` the matched filter's signal-to-noise ratio of the
//!    sampled pulse through the chain ([`crate::score::crb::PulseBound::snr`], bilinear in
//!    `ln d` between grid points), `eta` the scene's `trigger_sigmas`, so that the filter's
//!    false-alarm rate per offset, `Q(eta)`, is the kernel's trigger's per sample (a missed
//!    impact is decided neither right nor wrong). The same draws decided without noise give
//!    the noiseless ceiling of the scene's physics (every pulse found). For a law integrated,
//!    both duration features are scored on the same draws and the larger accuracy is the
//!    limit.
//!
//! The limit is an upper bound of what a detector of the features can reach in so far as the
//! bound is reached (the Cramér-Rao bound is the variance of an efficient estimator; at low
//! signal-to-noise ratio real estimators do worse), the pulse shape is known to the estimator
//! (only amplitude, time scale, onset and baseline unknown; the detection's filter knows the
//! time scale too, which a bank of filters over the scene's durations approaches). A clipped
//! sample counts with the information its censored reading keeps
//! ([`crate::score::crb::censored_share`]), so a pulse that clips is bounded from its flanks.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::bridge::calibrate::C_AREA;
use crate::physics::hertz64::{HertzImpact64, Material64};
use crate::physics::impact::{ImpactSpec, simulate};
use crate::physics::integrate::SimError;
use crate::physics::law_spec::LawSpec;
use crate::scene::{SceneError, SceneFile};
use crate::score::bayes::{
    ClassModel, FeatureNoise, class_models, gauss_legendre, gauss_pair, normal_pdf, phi,
};
use crate::score::crb::{FeatureCovariance, phase_averaged_bound};
use crate::sim::sensor::{ForcePulse, PulseShape, Sensor};

/// Default grid points per axis of a class's `(ln R, ln u)` box.
pub const DEFAULT_GRID: usize = 20;

/// Default Monte Carlo draws per class.
pub const DEFAULT_DRAWS_PER_CLASS: usize = 50_000;

/// Default onset phases the Cramér-Rao bound is averaged over.
pub const DEFAULT_PHASES: usize = 4;

/// Most Monte Carlo draws per class accepted.
pub const MAX_DRAWS_PER_CLASS: usize = 10_000_000;

/// Largest grid accepted (points per axis).
pub const MAX_GRID: usize = 64;

/// Standard deviation taken for a feature whose Fisher matrix is singular (a pulse that leaves
/// no trace in the samples): far wider than any class.
const NO_INFORMATION_SIGMA: f64 = 10.0;

/// Points per recorded pulse of the integrator.
const RECORD_POINTS: f64 = 512.0;

/// ChaCha8 stream of the reference Monte Carlo.
const RNG_REFERENCE: u64 = 12;

/// Which duration a reference's features take (module docs, step 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DurationFeature {
    /// First contact to the first zero of the force after its peak, in s.
    FirstZero,
    /// The impulse over the Hertz pulse's area factor, `J / (C_AREA F_max)`, in s.
    Impulse,
}

/// Options of [`reference_limit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceOptions {
    /// Grid points per axis of each class's box (`2..=MAX_GRID`).
    pub grid: usize,
    /// Monte Carlo draws per class (`1..=MAX_DRAWS_PER_CLASS`).
    pub draws_per_class: usize,
    /// Onset phases the bound is averaged over (`>= 1`).
    pub phases: usize,
}

impl Default for ReferenceOptions {
    /// [`DEFAULT_GRID`], [`DEFAULT_DRAWS_PER_CLASS`], [`DEFAULT_PHASES`].
    fn default() -> Self {
        Self {
            grid: DEFAULT_GRID,
            draws_per_class: DEFAULT_DRAWS_PER_CLASS,
            phases: DEFAULT_PHASES,
        }
    }
}

/// Why the reference limit could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The scene's sensor chain is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An impact of the grid could not be integrated.
    #[error("reference limit: class {class}, impact R {radius_m} m, u {speed_m_s} m/s: {error}")]
    Simulation {
        /// The class's name.
        class: String,
        /// Radius in m.
        radius_m: f64,
        /// Speed in m/s.
        speed_m_s: f64,
        /// The integrator's error.
        error: SimError,
    },
    /// An option is out of range.
    #[error("reference option {field} {problem}")]
    Option {
        /// The option.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
}

/// The reference limit of a scene (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceLimit {
    /// Best forced-choice accuracy from features measured at the Cramér-Rao bound.
    pub accuracy: f64,
    /// Its Monte Carlo standard error.
    pub std_error: f64,
    /// The same draws decided on their exact features: the noiseless ceiling.
    pub noiseless_accuracy: f64,
    /// Its standard error.
    pub noiseless_std_error: f64,
    /// `accuracy` of each class (draws of that class decided right), in the scene's order.
    pub per_class_accuracy: Vec<f64>,
    /// Monte Carlo draws, all classes.
    pub draws: usize,
    /// Mean bound standard deviation of `ln F_max` over the draws (dimensionless).
    pub mean_sigma_ln_force: f64,
    /// Mean bound standard deviation of `ln t_c` over the draws.
    pub mean_sigma_ln_duration: f64,
    /// `"hertz_closed_form"` (undamped Hertz for every class) or `"integrator"` (any class
    /// under another law, a yielding class included).
    pub features: &'static str,
    /// The duration the limit's features take (the larger limit of the two for an integrated
    /// law; [`DurationFeature::FirstZero`] for the closed forms, where both agree).
    pub duration_feature: DurationFeature,
    /// Grid points per axis.
    pub grid: usize,
    /// Onset phases averaged.
    pub phases: usize,
    /// The posterior a decision must reach to be confident, `1 - confident_error_rate`.
    pub confidence_threshold: f64,
    /// The coverage that threshold leaves at the limit under the scene's priors: the
    /// prior-weighted share of the draws whose Bayes posterior of the decided class, at the
    /// bound's noise, is at least `confidence_threshold`.
    pub coverage: f64,
    /// The prior-weighted share of those confident draws decided wrong (at most
    /// `1 - confidence_threshold` when the Bayes posteriors are exact, whatever the priors).
    pub confident_error_rate: f64,
    /// The prior-weighted share of the impacts found at all: the mean over the draws of the
    /// matched filter's detection probability `Phi(d - detection_sigmas)` (module docs,
    /// step 5; 1 when every pulse stands far above the noise).
    pub detected_share: f64,
    /// The matched filter's threshold in noise RMS (the scene's `trigger_sigmas`).
    pub detection_sigmas: f64,
}

/// A class's pulses at the points of its grid (see [`ClassMap::build_both`]).
struct GridPulses<'a> {
    /// The sphere's and the plate's material.
    material: Material64,
    plate: Material64,
    /// The class's contact law, and whether it is Hertz's (features in closed form).
    law: LawSpec,
    closed_form: bool,
    /// The class's Hertz power laws.
    model: ClassModel,
    /// The sensor whose bound is taken, at `phases` sample phases.
    sensor: &'a Sensor,
    phases: usize,
}

impl GridPulses<'_> {
    /// The two grid nodes at `(x, y) = (ln R, ln u)`: the features with the duration of the
    /// first zero and of the impulse, as deviations from the class's Hertz power laws, each
    /// with the phase-averaged Cramér-Rao covariance of the integrated pulse.
    fn nodes(&self, x: f64, y: f64) -> Result<[Node; 2], SimError> {
        let (radius_m, speed_m_s) = (x.exp(), y.exp());
        let hertz = HertzImpact64::new(&self.material, &self.plate, radius_m, speed_m_s)?;
        let mut spec = ImpactSpec::new(self.material, self.plate, radius_m, speed_m_s);
        spec.law = self.law;
        let step_s = hertz.duration_s / RECORD_POINTS;
        spec.record = Some(step_s);
        let report = simulate(&spec)?;
        let f_max = report.peak_force_n;
        let [zero_f, impulse_f] = if self.closed_form {
            [[hertz.peak_force_n.ln(), hertz.duration_s.ln()]; 2]
        } else {
            [
                [f_max.ln(), report.pulse_duration_s.ln()],
                [f_max.ln(), (report.impulse_n_s / (C_AREA * f_max)).ln()],
            ]
        };
        let pulse = ForcePulse {
            start_s: 0.0,
            duration_s: report.duration_s,
            scale: 1.0,
            shape: PulseShape::Series {
                step_s,
                force_n: report
                    .force_series
                    .unwrap_or_default()
                    .into_iter()
                    .map(|(_, f)| f)
                    .collect(),
            },
        };
        let bound = phase_averaged_bound(self.sensor, &pulse, self.phases);
        let (cov, snr) = (bound.covariance, bound.snr);
        let hertz_f = self.model.forward(x, y);
        let deviation = |f: [f64; 2]| [f[0] - hertz_f.0, f[1] - hertz_f.1];
        Ok([
            node(deviation(zero_f), cov, snr),
            node(deviation(impulse_f), cov, snr),
        ])
    }
}

/// One grid point: deviation from the Hertz power laws, log standard deviations, correlation,
/// and the log of the matched filter's signal-to-noise ratio ([`crate::score::crb::
/// PulseBound::snr`], capped at [`DETECTED_SNR`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    deviation: [f64; 2],
    ln_sigma: [f64; 2],
    correlation: f64,
    ln_snr: f64,
}

/// The matched filter's signal-to-noise ratio taken for a pulse that is certainly found (and
/// the cap of every grid point's): `Phi(1e6 - eta)` is 1 in f64.
const DETECTED_SNR: f64 = 1e6;

/// The features and their bound at one point of a class's box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFeatures {
    /// `(ln F_max, ln t_c)`.
    pub features: [f64; 2],
    /// `d features / d (ln R, ln u)`, rows the features.
    pub jacobian: [[f64; 2]; 2],
    /// `[var ln F, var ln t_c, cov]` of the bound.
    pub covariance: FeatureCovariance,
}

/// The grid cell about a point of a class's box and the point's place in it (see
/// [`ClassMap::cell`]).
struct Cell<'a> {
    /// The cell's corner nodes: `(x, y)`, `(x + 1, y)`, `(x, y + 1)`, `(x + 1, y + 1)`.
    corners: [&'a Node; 4],
    /// The point's fractions of the cell along `x` and `y`.
    fx: f64,
    fy: f64,
    /// `d fraction / d (x, y)` (0 outside the box, where the map is clamped).
    dgx: f64,
    dgy: f64,
}

impl Cell<'_> {
    /// The bilinear interpolation of `v` over the cell at the point, and its derivatives in
    /// `x` and `y`.
    fn lerp(&self, v: impl Fn(&Node) -> f64) -> (f64, f64, f64) {
        let [a, b, c, d] = self.corners.map(v);
        let (fx, fy) = (self.fx, self.fy);
        let value =
            a * (1.0 - fx) * (1.0 - fy) + b * fx * (1.0 - fy) + c * (1.0 - fx) * fy + d * fx * fy;
        let d_dx = ((b - a) * (1.0 - fy) + (d - c) * fy) * self.dgx;
        let d_dy = ((c - a) * (1.0 - fx) + (d - b) * fx) * self.dgy;
        (value, d_dx, d_dy)
    }
}

/// One class's features and noise over its prior box, interpolated from a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ClassMap {
    /// The class's Hertz power laws and prior.
    pub model: ClassModel,
    grid: usize,
    phases: usize,
    features: &'static str,
    duration: DurationFeature,
    nodes: Vec<Node>,
    /// The matched filter's threshold `eta` in noise RMS: the scene's `trigger_sigmas`, so
    /// that its false-alarm rate per offset, `Q(eta)`, is the trigger's per sample.
    pub detection_sigmas: f64,
}

impl ClassMap {
    /// The maps of class `class` of `scene` with durations read from the first zero and from
    /// the impulse (see the module docs, steps 1-3), from one integration and one bound per
    /// grid point (the bound does not depend on how the duration is read).
    pub fn build_both(
        scene: &SceneFile,
        class: usize,
        sensor: &Sensor,
        opts: &ReferenceOptions,
    ) -> Result<[Self; 2], ReferenceError> {
        let model = class_models(scene)[class];
        let c = &scene.classes[class];
        let (material, plate) = (c.material.material(), scene.plate.material());
        let law = scene
            .class_law(class)
            .map_err(|error| ReferenceError::Simulation {
                class: c.name.clone(),
                radius_m: c.radius_m.min,
                speed_m_s: c.speed_range_m_s().min,
                error,
            })?;
        let closed_form = matches!(law, LawSpec::Hertz);
        let at = GridPulses {
            material,
            plate,
            law,
            closed_form,
            model,
            sensor,
            phases: opts.phases,
        };
        let n = opts.grid;
        let (mut first_zero, mut impulse) = (Vec::with_capacity(n * n), Vec::with_capacity(n * n));
        for j in 0..n {
            for i in 0..n {
                let (x, y) = grid_point(&model, n, i, j);
                let [zero_node, impulse_node] =
                    at.nodes(x, y).map_err(|error| ReferenceError::Simulation {
                        class: c.name.clone(),
                        radius_m: x.exp(),
                        speed_m_s: y.exp(),
                        error,
                    })?;
                first_zero.push(zero_node);
                impulse.push(impulse_node);
            }
        }
        let map = |duration, nodes| Self {
            model,
            grid: n,
            phases: opts.phases,
            features: if closed_form {
                "hertz_closed_form"
            } else {
                "integrator"
            },
            duration,
            nodes,
            detection_sigmas: f64::from(scene.settings.trigger_sigmas),
        };
        Ok([
            map(DurationFeature::FirstZero, first_zero),
            map(DurationFeature::Impulse, impulse),
        ])
    }

    /// The same map with the noise replaced by `noise` everywhere, and every pulse found.
    pub fn with_constant_noise(mut self, noise: &FeatureNoise) -> Self {
        let cov = [
            noise.sigma_ln_force.powi(2),
            noise.sigma_ln_duration.powi(2),
            noise.correlation * noise.sigma_ln_force * noise.sigma_ln_duration,
        ];
        for n in &mut self.nodes {
            *n = node(n.deviation, Some(cov), DETECTED_SNR);
        }
        self
    }

    /// The grid cell about `(x, y) = (ln R, ln u)`, clamped to the box.
    fn cell(&self, x: f64, y: f64) -> Cell<'_> {
        let (x0, x1) = self.model.ln_radius;
        let (y0, y1) = self.model.ln_speed;
        let last = (self.grid - 1) as f64;
        let place = |v: f64, lo: f64, hi: f64| -> (usize, f64, f64) {
            let g = ((v - lo) / (hi - lo) * last).clamp(0.0, last);
            let i = (g.floor() as usize).min(self.grid - 2);
            let inside = v > lo && v < hi;
            (i, g - i as f64, if inside { last / (hi - lo) } else { 0.0 })
        };
        let (i, fx, dgx) = place(x, x0, x1);
        let (j, fy, dgy) = place(y, y0, y1);
        let q = |a: usize, b: usize| &self.nodes[(j + b) * self.grid + i + a];
        Cell {
            corners: [q(0, 0), q(1, 0), q(0, 1), q(1, 1)],
            fx,
            fy,
            dgx,
            dgy,
        }
    }

    /// Features, Jacobian and bound at `(x, y) = (ln R, ln u)` (bilinear between grid points,
    /// clamped to the box: outside it the deviation and the noise of its edge).
    pub fn at(&self, x: f64, y: f64) -> LocalFeatures {
        let cell = self.cell(x, y);
        let (df, dfx, dfy) = cell.lerp(|n| n.deviation[0]);
        let (dt, dtx, dty) = cell.lerp(|n| n.deviation[1]);
        let sf = cell.lerp(|n| n.ln_sigma[0]).0.exp();
        let st = cell.lerp(|n| n.ln_sigma[1]).0.exp();
        let r = cell.lerp(|n| n.correlation).0;
        let (hf, ht) = self.model.forward(x, y);
        LocalFeatures {
            features: [hf + df, ht + dt],
            jacobian: [[2.0 + dfx, 1.2 + dfy], [1.0 + dtx, -0.2 + dty]],
            covariance: [sf * sf, st * st, r * sf * st],
        }
    }

    /// The probability that a pulse at `(x, y) = (ln R, ln u)` is found at all,
    /// `Phi(d - eta)`: `d` the matched filter's signal-to-noise ratio (bilinear in `ln d`
    /// between grid points), `eta` the map's [`ClassMap::detection_sigmas`]. Apart from
    /// [`ClassMap::at`], which the preimage's Newton steps call, since only the draws need it.
    pub fn detection(&self, x: f64, y: f64) -> f64 {
        let snr = self.cell(x, y).lerp(|n| n.ln_snr).0.exp();
        phi(snr - self.detection_sigmas)
    }

    /// `z* = g^-1(f)` by Newton's method from the Hertz inverse (see the module docs), each
    /// step halved until it lowers the residual `|g(z) - f|^2` (at most 20 times): `g` is
    /// bilinear per grid cell, so its Jacobian jumps between cells, and a full step can cycle
    /// between them where a law's deviation from Hertz changes fast over the box (Adams with a
    /// fixed `c_max`: there the full steps left 1.7 % of the limit's confident decisions wrong
    /// at a threshold of 0.99).
    fn preimage(&self, f: [f64; 2]) -> (f64, f64) {
        let residual = |x: f64, y: f64| {
            let l = self.at(x, y);
            ([l.features[0] - f[0], l.features[1] - f[1]], l.jacobian)
        };
        let norm2 = |r: [f64; 2]| r[0] * r[0] + r[1] * r[1];
        let (mut x, mut y) = self.model.invert(f[0], f[1]);
        let (mut r, mut jac) = residual(x, y);
        for _ in 0..60 {
            let [[a, b], [c, d]] = jac;
            let det = a * d - b * c;
            let (dx, dy) = ((d * r[0] - b * r[1]) / det, (a * r[1] - c * r[0]) / det);
            let mut step = 1.0;
            let (nx, ny, nr, nj) = loop {
                let (nx, ny) = (x - step * dx, y - step * dy);
                let (nr, nj) = residual(nx, ny);
                // A residual at rounding level takes the full step (no descent to find).
                if norm2(nr) < norm2(r) || norm2(r) < 1e-26 || step < 1e-6 {
                    break (nx, ny, nr, nj);
                }
                step *= 0.5;
            };
            (x, y, r, jac) = (nx, ny, nr, nj);
            if (step * dx).abs() + (step * dy).abs() < 1e-13 {
                break;
            }
        }
        (x, y)
    }

    /// `p(f | class)` with the bound's noise (`noisy`) or without (see the module docs,
    /// step 4); per unit of `ln F_max` and `ln t_c`.
    pub fn density(&self, f: [f64; 2], noisy: bool) -> f64 {
        let (mx, my) = self.preimage(f);
        let l = self.at(mx, my);
        let [[a, b], [c, d]] = l.jacobian;
        let det = a * d - b * c;
        let (x0, x1) = self.model.ln_radius;
        let (y0, y1) = self.model.ln_speed;
        let px = 1.0 / (x1 - x0);
        if !noisy {
            let inside = mx >= x0 && mx <= x1;
            return if inside {
                px * self.model.speed_density(my) / det.abs()
            } else {
                0.0
            };
        }
        // Sigma_z = J^-1 S J^-T, J^-1 = [[d, -b], [-c, a]] / det.
        let [sff, stt, sft] = l.covariance;
        let (ia, ib, ic, id) = (d / det, -b / det, -c / det, a / det);
        let sxx = ia * ia * sff + 2.0 * ia * ib * sft + ib * ib * stt;
        let syy = ic * ic * sff + 2.0 * ic * id * sft + id * id * stt;
        let sxy = ia * ic * sff + (ia * id + ib * ic) * sft + ib * id * stt;
        let sy = syy.sqrt();
        let lo = y0.max(my - 8.0 * sy);
        let hi = y1.min(my + 8.0 * sy);
        if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
            return 0.0;
        }
        // x given y: mean mx + sxy / syy (y - my), variance sxx - sxy^2 / syy.
        let cond_s = (sxx - sxy * sxy / syy).max(1e-30).sqrt();
        let integrand = |y: f64| {
            let gy = normal_pdf((y - my) / sy) / sy;
            let m = mx + sxy / syy * (y - my);
            let px_box = phi((x1 - m) / cond_s) - phi((x0 - m) / cond_s);
            self.model.speed_density(y) * gy * px_box
        };
        let mid = 0.5 * (lo + hi);
        let integral = gauss_legendre(lo, mid, integrand) + gauss_legendre(mid, hi, integrand);
        px * integral / det.abs()
    }
}

/// Grid point `(i, j)` of a class's box in `(ln R, ln u)`.
fn grid_point(model: &ClassModel, n: usize, i: usize, j: usize) -> (f64, f64) {
    let (x0, x1) = model.ln_radius;
    let (y0, y1) = model.ln_speed;
    let t = |k: usize| k as f64 / (n - 1) as f64;
    (x0 + (x1 - x0) * t(i), y0 + (y1 - y0) * t(j))
}

/// A grid node from its deviation, its covariance (`None`: no information) and the matched
/// filter's signal-to-noise ratio `snr`.
fn node(deviation: [f64; 2], cov: Option<FeatureCovariance>, snr: f64) -> Node {
    let wide = NO_INFORMATION_SIGMA.ln();
    let ln_snr = snr.clamp(1e-12, DETECTED_SNR).ln();
    match cov {
        Some([vf, vt, c]) if vf > 0.0 && vt > 0.0 && vf.is_finite() && vt.is_finite() => Node {
            deviation,
            ln_sigma: [0.5 * vf.ln(), 0.5 * vt.ln()],
            correlation: (c / (vf * vt).sqrt()).clamp(-0.999, 0.999),
            ln_snr,
        },
        _ => Node {
            deviation,
            ln_sigma: [wide, wide],
            correlation: 0.0,
            ln_snr,
        },
    }
}

/// The class maps of every class of `scene`, durations read from the first zero.
pub fn class_maps(
    scene: &SceneFile,
    opts: &ReferenceOptions,
) -> Result<Vec<ClassMap>, ReferenceError> {
    class_maps_with(scene, opts, DurationFeature::FirstZero)
}

/// The class maps of every class of `scene`, durations read as `duration`.
pub fn class_maps_with(
    scene: &SceneFile,
    opts: &ReferenceOptions,
    duration: DurationFeature,
) -> Result<Vec<ClassMap>, ReferenceError> {
    let [first_zero, impulse] = class_maps_both(scene, opts)?;
    Ok(match duration {
        DurationFeature::FirstZero => first_zero,
        DurationFeature::Impulse => impulse,
    })
}

/// The class maps of every class of `scene`, durations read from the first zero and from the
/// impulse ([`ClassMap::build_both`]).
pub fn class_maps_both(
    scene: &SceneFile,
    opts: &ReferenceOptions,
) -> Result<[Vec<ClassMap>; 2], ReferenceError> {
    let opt = |field, problem: &str| ReferenceError::Option {
        field,
        problem: problem.into(),
    };
    if !(2..=MAX_GRID).contains(&opts.grid) {
        return Err(opt("grid", "must be in 2..=64"));
    }
    if opts.phases == 0 || opts.phases > 64 {
        return Err(opt("phases", "must be in 1..=64"));
    }
    let sensor = Sensor::new(&scene.sensor)?;
    let (mut first_zero, mut impulse) = (Vec::new(), Vec::new());
    for c in 0..scene.classes.len() {
        let [z, i] = ClassMap::build_both(scene, c, &sensor, opts)?;
        first_zero.push(z);
        impulse.push(i);
    }
    Ok([first_zero, impulse])
}

/// The Bayes-optimal class of observed features `f` among `maps` (largest prior times
/// density).
pub fn decide(maps: &[ClassMap], f: [f64; 2], noisy: bool) -> usize {
    maps.iter()
        .map(|m| m.model.prior * m.density(f, noisy))
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |best, (i, score)| {
            if score > best.1 { (i, score) } else { best }
        })
        .0
}

/// [`decide`] at the bound's noise, and the Bayes posterior of the class it decides,
/// `prior_c p(f | c) / sum_j prior_j p(f | j)` (0 where every density vanishes).
pub fn decide_with_posterior(maps: &[ClassMap], f: [f64; 2]) -> (usize, f64) {
    let scores: Vec<f64> = maps
        .iter()
        .map(|m| m.model.prior * m.density(f, true))
        .collect();
    let total: f64 = scores.iter().sum();
    let (best, top) =
        scores.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &v)| if v > b.1 { (i, v) } else { b },
        );
    (best, if total > 0.0 { top / total } else { 0.0 })
}

/// The Monte Carlo of the module docs, step 5, on `maps`, `draws_per_class` draws per class
/// from `uniform` (numbers in `(0, 1)`); a decision is confident when its posterior reaches
/// `confidence_threshold`.
pub fn reference_accuracy(
    maps: &[ClassMap],
    draws_per_class: usize,
    confidence_threshold: f64,
    uniform: &mut impl FnMut() -> f64,
) -> ReferenceLimit {
    let total_prior: f64 = maps.iter().map(|m| m.model.prior).sum();
    let n = draws_per_class.max(1);
    let (mut acc, mut acc0, mut sum_sf, mut sum_st) = (0.0, 0.0, 0.0, 0.0);
    let (mut covered, mut covered_wrong, mut detected_share) = (0.0, 0.0, 0.0);
    let mut per_class_accuracy = Vec::with_capacity(maps.len());
    for (i, m) in maps.iter().enumerate() {
        let ClassDraws {
            right,
            right0,
            sure,
            sure_wrong,
            detected,
        } = draw_class(
            maps,
            i,
            n,
            confidence_threshold,
            uniform,
            (&mut sum_sf, &mut sum_st),
        );
        let w = m.model.prior / total_prior;
        let a = right / n as f64;
        per_class_accuracy.push(a);
        acc += w * a;
        acc0 += w * right0 as f64 / n as f64;
        covered += w * sure / n as f64;
        covered_wrong += w * sure_wrong / n as f64;
        detected_share += w * detected / n as f64;
    }
    let draws = n * maps.len();
    let se = |a: f64| (a * (1.0 - a) / draws as f64).sqrt();
    ReferenceLimit {
        accuracy: acc,
        std_error: se(acc),
        noiseless_accuracy: acc0,
        noiseless_std_error: se(acc0),
        per_class_accuracy,
        draws,
        mean_sigma_ln_force: sum_sf / draws as f64,
        mean_sigma_ln_duration: sum_st / draws as f64,
        features: features_of(maps),
        duration_feature: maps
            .first()
            .map_or(DurationFeature::FirstZero, |m| m.duration),
        grid: maps.first().map_or(0, |m| m.grid),
        phases: maps.first().map_or(0, |m| m.phases),
        confidence_threshold,
        coverage: covered,
        confident_error_rate: if covered > 0.0 {
            covered_wrong / covered
        } else {
            0.0
        },
        detected_share,
        detection_sigmas: maps.first().map_or(0.0, |m| m.detection_sigmas),
    }
}

/// Where the maps' features come from: `hertz_closed_form` when every map's do, else
/// `integrator`.
fn features_of(maps: &[ClassMap]) -> &'static str {
    if maps.iter().all(|m| m.features == "hertz_closed_form") {
        "hertz_closed_form"
    } else {
        "integrator"
    }
}

/// What the draws of one class gave (see [`draw_class`]), each noisy draw weighted by the
/// probability that its pulse is found.
struct ClassDraws {
    /// Right decisions on the noisy features (found), and on the noiseless ones.
    right: f64,
    right0: usize,
    /// Confident decisions (posterior at the threshold or above), and the wrong among them.
    sure: f64,
    sure_wrong: f64,
    /// The sum of the draws' detection probabilities.
    detected: f64,
}

/// `n` draws of class `i` of `maps` from `uniform`, each decided on its features with the
/// bound's correlated Gaussian noise ([`decide_with_posterior`], confident at
/// `confidence_threshold`), weighted by the probability that its pulse is found
/// ([`ClassMap::detection`]: a pulse not found is decided neither right nor wrong, as a
/// missed impact is scored), and without noise ([`decide`]); each draw's `sigma ln F` and
/// `sigma ln t` are added to `sums`, in draw order.
fn draw_class(
    maps: &[ClassMap],
    i: usize,
    n: usize,
    confidence_threshold: f64,
    uniform: &mut impl FnMut() -> f64,
    sums: (&mut f64, &mut f64),
) -> ClassDraws {
    let m = &maps[i];
    let (sum_sf, sum_st) = sums;
    let mut d = ClassDraws {
        right: 0.0,
        right0: 0,
        sure: 0.0,
        sure_wrong: 0.0,
        detected: 0.0,
    };
    for _ in 0..n {
        let (x, y) = m.model.sample(uniform(), uniform());
        let l = m.at(x, y);
        let [vf, vt, c] = l.covariance;
        let (sf, st) = (vf.sqrt(), vt.sqrt());
        let r = c / (sf * st);
        let (g1, g2) = gauss_pair(uniform);
        let f = l.features;
        let noisy = [
            f[0] + sf * g1,
            f[1] + st * (r * g1 + (1.0 - r * r).max(0.0).sqrt() * g2),
        ];
        let (class, posterior) = decide_with_posterior(maps, noisy);
        let found = m.detection(x, y);
        d.detected += found;
        d.right += found * f64::from(u8::from(class == i));
        if posterior >= confidence_threshold {
            d.sure += found;
            d.sure_wrong += found * f64::from(u8::from(class != i));
        }
        d.right0 += (decide(maps, f, false) == i) as usize;
        *sum_sf += sf;
        *sum_st += st;
    }
    d
}

/// The reference limit of `scene` (see the module docs), Monte Carlo seeded with `seed`, with
/// the coverage that `confidence_threshold` leaves at it.
pub fn reference_limit(
    scene: &SceneFile,
    opts: &ReferenceOptions,
    seed: u64,
    confidence_threshold: f64,
) -> Result<ReferenceLimit, ReferenceError> {
    if !(1..=MAX_DRAWS_PER_CLASS).contains(&opts.draws_per_class) {
        return Err(ReferenceError::Option {
            field: "draws_per_class",
            problem: format!("must be in 1..={MAX_DRAWS_PER_CLASS}"),
        });
    }
    let [first_zero, impulse] = class_maps_both(scene, opts)?;
    let limit = |maps: &[ClassMap]| {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(RNG_REFERENCE);
        let mut uniform = || ((rng.random::<u64>() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        reference_accuracy(
            maps,
            opts.draws_per_class,
            confidence_threshold,
            &mut uniform,
        )
    };
    let first_zero = limit(&first_zero);
    if first_zero.features == "hertz_closed_form" {
        return Ok(first_zero);
    }
    let impulse = limit(&impulse);
    Ok(if impulse.accuracy > first_zero.accuracy {
        impulse
    } else {
        first_zero
    })
}
