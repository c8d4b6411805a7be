//! The Hertz envelope of one particle class: an exact parallelogram in log space.
//!
//! From [`crate::hertz`], `F_max = c_F R^2 u^(6/5)` and `t_c = c_t R u^(-1/5)` with
//! `c_F = 4/3 E*^(2/5) (5 pi rho / 4)^(3/5)` and `c_t = 2.9432752 (5 pi rho / (4 E*))^(2/5)`.
//! In `x = ln R`, `y = ln u`, `(ln F_max, ln t_c) = (ln c_F + 2x + 6y/5, ln c_t + x - y/5)`:
//! a linear map with determinant `-8/5`. A class with `R` in `[R0, R1]` and `u` in `[u0, u1]`
//! therefore fills an exact parallelogram, and every observed `(F_max, t_c)` inverts exactly to
//! the `(R, u)` the class would need:
//! `y = (ln F - ln c_F - 2 (ln t - ln c_t)) / (8/5)`, `x = ln t - ln c_t + y/5`.
//!
//! A class whose pulses are not Hertz's bends the parallelogram by its measured/Hertz ratios,
//! functions of one direction `s = a ln R + b ln u` of its plane ([`crate::ratio_map`]:
//! Thornton's yield along `ln u`, a fixed-coefficient damped law along its damping ratio): the
//! same inverse with a table lookup for `s`, and the map's local Jacobian in place of `8/5`.
//!
//! Priors: `R` log-uniform on `[R0, R1]`; `u` with density `p(u) ~ u^(beta - 1)` on `[u0, u1]`
//! (`beta = 1`: uniform speed; `beta = 2`: uniform drop height, `u = sqrt(2 g h)`).

use crate::chain_bias::ChainSpread;
use crate::error::{Error, positive, representable};
use crate::hertz::CONTACT_TIME_FACTOR;
use crate::math::{self, Backend};
use crate::ratio_map::{Local, RatioMap};
#[cfg(feature = "plasticity")]
use crate::thornton::yield_speed_in;

/// `|det|` of the map `(ln R, ln u) -> (ln F_max, ln t_c)`.
pub const JACOBIAN: f32 = 1.6;

/// Smallest standard deviation (in log units) the likelihood uses, so it stays finite.
const MIN_SIGMA: f32 = 1e-4;

/// Largest standard deviation of `ln R` or `ln u` the likelihood uses (a factor `e^4 = 55`,
/// more than any class spans): past it a measurement says nothing more along that axis, and
/// the tilted likelihood's tails (`Phi` at `-beta sigma`) would leave f32.
pub const MAX_SIGMA: f32 = 4.0;

/// A closed interval `[min, max]` with `min < max`, both finite and `> 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Range {
    /// Lower end.
    pub min: f32,
    /// Upper end.
    pub max: f32,
}

impl Range {
    /// `[min, max]`; checked where it is used ([`Range::checked`]).
    pub const fn new(min: f32, max: f32) -> Self {
        Self { min, max }
    }

    /// Checks that both ends are finite, `> 0` and `min < max`.
    pub fn checked(self, what: &'static str) -> Result<Self, Error> {
        positive(self.min, what)?;
        positive(self.max, what)?;
        if self.min >= self.max {
            return Err(Error::InvertedRange(what));
        }
        Ok(self)
    }
}

/// Which way an observation lies outside an envelope, in terms of the radius or speed the class
/// would need to produce it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Side {
    /// Below the class's range.
    Below,
    /// Inside the class's range.
    Inside,
    /// Above the class's range.
    Above,
}

/// The envelope of one class in `(ln F_max, ln t_c)`, with its prior density.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Envelope {
    /// `ln c_F` (c_F in N m^-2 (m/s)^(-6/5)).
    pub ln_force_coeff: f32,
    /// `ln c_t` (c_t in s m^-1 (m/s)^(1/5)).
    pub ln_duration_coeff: f32,
    /// `[ln R0, ln R1]`, R in m.
    pub ln_radius: (f32, f32),
    /// `[ln u0, ln u1]`, u in m/s.
    pub ln_speed: (f32, f32),
    /// Speed prior exponent `beta`: `p(ln u) ~ e^(beta ln u)`.
    pub speed_beta: f32,
    /// `ln` of the constant part of the prior density in `(ln F, ln t)`:
    /// `-ln(x1 - x0) - ln(8/5) + ln(beta / (e^(beta y1) (1 - e^(beta (y0 - y1)))))`
    /// (`-ln(y1 - y0)` in place of the last term for `beta = 0`); for a bent class the
    /// density adds `ln(8/5 / J)` at the point ([`Envelope::ln_density_excess`]).
    pub ln_normalizer: f32,
    /// The ratio map that bends the envelope (Thornton's yield, or a table of a damped law's
    /// ratios); `None`: the Hertz parallelogram. Only with the `ratio_map` feature (without it
    /// every envelope is Hertz's and carries no table).
    #[cfg(feature = "ratio_map")]
    pub ratio_map: Option<RatioMap>,
}

/// How `(x, y) = (ln R, ln u)` move with `(ln F_max, ln t_c)`: `((dx/dA, dx/dB), (dy/dA,
/// dy/dB))`.
pub type Slopes = ((f32, f32), (f32, f32));

/// Hertz's [`Slopes`]: `x = ln F / 8 + 3 ln t / 4 + k`, `y = 5 ln F / 8 - 5 ln t / 4 + k`.
pub const HERTZ_SLOPES: Slopes = ((0.125, 0.75), (0.625, -1.25));

/// Measurement noise carried from `(ln F_max, ln t_c)`, with standard deviations `sF`, `sT`
/// and covariance `c`, into `(x, y) = (ln R, ln u)` as the standard deviations of its two
/// marginals: `sigma_x^2 = sF^2 / 64 + 9 sT^2 / 16 + 3 c / 16`,
/// `sigma_y^2 = (sF^2 + 4 sT^2 - 4 c) / 2.56` (from `x = ln F / 8 + 3 ln t / 4 + k`,
/// `y = 5 ln F / 8 - 5 ln t / 4 + k`), each at least `1e-4`. The likelihood takes the two as
/// independent: exact along one edge of a class's box, approximate at its corners.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseXy {
    /// Standard deviation of `ln R`.
    pub sigma_x: f32,
    /// Standard deviation of `ln u`.
    pub sigma_y: f32,
}

impl NoiseXy {
    /// From the standard deviations of `ln F_max` and `ln t_c` and their covariance
    /// `cov_ln` (log units squared).
    ///
    /// ```
    /// use coalshock::envelope::NoiseXy;
    /// use coalshock::math::Libm as M;
    /// // A peak 1 % off with the area exact: ln t_c moves by the opposite, and (ln R, ln u)
    /// // by (-5/8, 15/8) of it.
    /// let n = NoiseXy::new::<M>(0.01, 0.01, -1e-4);
    /// assert!((n.sigma_x - 0.00625).abs() < 1e-6 && (n.sigma_y - 0.01875).abs() < 1e-6);
    /// ```
    pub fn new<M: Backend>(sigma_ln_force: f32, sigma_ln_duration: f32, cov_ln: f32) -> Self {
        let f2 = sigma_ln_force * sigma_ln_force;
        let t2 = sigma_ln_duration * sigma_ln_duration;
        let var_x = f2 / 64.0 + 0.5625 * t2 + 0.1875 * cov_ln;
        let var_y = (f2 + 4.0 * t2 - 4.0 * cov_ln) / (JACOBIAN * JACOBIAN);
        Self {
            sigma_x: clamp_sigma(M::sqrt(var_x.max(0.0))),
            sigma_y: clamp_sigma(M::sqrt(var_y.max(0.0))),
        }
    }
}

impl NoiseXy {
    /// From the standard deviations of `ln F_max` and `ln t_c` and their covariance `c`
    /// through a bent class's map at a point with slopes `l` ([`Local`]):
    /// `dx = dx_A d ln F + dx_B d ln t` (likewise `y`), so
    /// `sigma_x^2 = dx_A^2 sF^2 + dx_B^2 sT^2 + 2 dx_A dx_B c` (likewise `y`)
    /// ([`NoiseXy::new`] for Hertz's `(1/8, 3/4)`, `(5/8, -5/4)`).
    pub fn through<M: Backend>(
        sigma_ln_force: f32,
        sigma_ln_duration: f32,
        cov_ln: f32,
        l: Local,
    ) -> Self {
        let f2 = sigma_ln_force * sigma_ln_force;
        let t2 = sigma_ln_duration * sigma_ln_duration;
        let var =
            |(ca, cb): (f32, f32)| (ca * ca * f2 + cb * cb * t2 + 2.0 * ca * cb * cov_ln).max(0.0);
        Self {
            sigma_x: clamp_sigma(M::sqrt(var(l.dx))),
            sigma_y: clamp_sigma(M::sqrt(var(l.dy))),
        }
    }

    /// This noise widened by a chain's spread `s` ([`ChainSpread`]: second moments of
    /// `(ln F_max, ln t_c)`), carried by the slopes `(dx, dy)` of `(x, y)` in `(ln F_max,
    /// ln t_c)` ([`HERTZ_SLOPES`] or a bent class's [`Local`]) and added to each variance:
    /// `sigma_x^2 + dx_A^2 vF + dx_B^2 vT + 2 dx_A dx_B cFT` (likewise `y`), at most
    /// [`MAX_SIGMA`].
    ///
    /// ```
    /// use coalshock::chain_bias::ChainSpread;
    /// use coalshock::envelope::{HERTZ_SLOPES, NoiseXy};
    /// use coalshock::math::Libm as M;
    /// // A bias b of ln F_max with -b of ln t_c moves (ln R, ln u) by (-5/8 b, 15/8 b).
    /// let b2 = 1e-4;
    /// let s = ChainSpread { var_ln_force: b2, var_ln_duration: b2, cov_ln: -b2 };
    /// let n = NoiseXy { sigma_x: 1e-4, sigma_y: 1e-4 }.with_chain::<M>(&s, HERTZ_SLOPES);
    /// assert!((n.sigma_x - (1e-8f32 + 0.390625 * b2).sqrt()).abs() < 1e-6);
    /// assert!((n.sigma_y - (1e-8f32 + 3.515625 * b2).sqrt()).abs() < 1e-6);
    /// ```
    pub fn with_chain<M: Backend>(self, s: &ChainSpread, (dx, dy): Slopes) -> Self {
        if *s == ChainSpread::ZERO {
            return self;
        }
        let var = |sigma: f32, (ca, cb): (f32, f32)| {
            sigma * sigma
                + ca * ca * s.var_ln_force
                + cb * cb * s.var_ln_duration
                + 2.0 * ca * cb * s.cov_ln
        };
        // A spread's second moments are positive semi-definite: each variance only grows, and
        // stays at least `MIN_SIGMA^2`.
        Self {
            sigma_x: M::sqrt(var(self.sigma_x, dx)).min(MAX_SIGMA),
            sigma_y: M::sqrt(var(self.sigma_y, dy)).min(MAX_SIGMA),
        }
    }
}

/// Where an observation maps in a class's `(ln R, ln u)` plane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Inverted {
    /// Radius in m the class would need.
    pub radius_m: f32,
    /// Speed in m/s the class would need.
    pub speed_m_s: f32,
    /// Where that radius lies against the class's range.
    pub radius_side: Side,
    /// Where that speed lies against the class's range.
    pub speed_side: Side,
}

impl Envelope {
    /// The envelope of a sphere material (`density_kg_m3`, effective modulus against the plate
    /// `effective_modulus_pa`) with radius in `radius_m` and speed in `speed_m_s`.
    ///
    /// `ln c_F = ln(4/3) + (2/5) ln E* + (3/5) ln(5 pi rho / 4)`,
    /// `ln c_t = ln 2.9432752 + (2/5) (ln(5 pi rho / 4) - ln E*)`.
    pub fn new<M: Backend>(
        effective_modulus_pa: f32,
        density_kg_m3: f32,
        radius_m: Range,
        speed_m_s: Range,
        speed_beta: f32,
    ) -> Result<Self, Error> {
        let e = positive(effective_modulus_pa, "effective_modulus_pa")?;
        let rho = positive(density_kg_m3, "density_kg_m3")?;
        let r = radius_m.checked("radius_m")?;
        let u = speed_m_s.checked("speed_m_s")?;
        let ln_e = M::ln(e);
        let ln_rho = M::ln(5.0 * core::f32::consts::PI / 4.0 * rho);
        let (x0, x1) = (M::ln(r.min), M::ln(r.max));
        let (y0, y1) = (M::ln(u.min), M::ln(u.max));
        // A range narrower than f32 resolves in log space would divide by zero below.
        if x1 - x0 < 1e-4 {
            return Err(Error::OutOfRange(
                "radius_m (range narrower than 1e-4 relative)",
            ));
        }
        if y1 - y0 < 1e-4 {
            return Err(Error::OutOfRange(
                "speed_m_s (range narrower than 1e-4 relative)",
            ));
        }
        let b = speed_beta;
        let ln_py = if b.abs() < 1e-6 {
            -M::ln(y1 - y0)
        } else {
            M::ln(b / (1.0 - M::exp(b * (y0 - y1)))) - b * y1
        };
        let env = Self {
            ln_force_coeff: M::ln(4.0 / 3.0) + 0.4 * ln_e + 0.6 * ln_rho,
            ln_duration_coeff: M::ln(CONTACT_TIME_FACTOR) + 0.4 * (ln_rho - ln_e),
            ln_radius: (x0, x1),
            ln_speed: (y0, y1),
            speed_beta,
            ln_normalizer: -M::ln(x1 - x0) - M::ln(JACOBIAN) + ln_py,
            #[cfg(feature = "ratio_map")]
            ratio_map: None,
        };
        if !env.ln_normalizer.is_finite() {
            return Err(Error::Unrepresentable("prior density"));
        }
        // Every corner must give a peak force and duration that f32 carries.
        for (x, y) in env.corners() {
            let (lf, lt) = env.forward(x, y);
            representable(M::exp(lf), "peak force")?;
            representable(M::exp(lt), "contact duration")?;
        }
        Ok(env)
    }

    /// The envelope bent by Thornton's yield at the limiting contact pressure
    /// `yield_pressure_pa` (Pa), for the same material (`effective_modulus_pa`,
    /// `density_kg_m3`) as [`Envelope::new`]: its [`RatioMap::thornton`] over the class's
    /// speed range from the yield speed `V_y = 1.5605 (p_y^5 / (E*^4 rho))^(1/2)`.
    #[cfg(feature = "plasticity")]
    #[inline(never)]
    pub fn yielding<M: Backend>(
        self,
        effective_modulus_pa: f32,
        density_kg_m3: f32,
        yield_pressure_pa: f32,
    ) -> Result<Self, Error> {
        let v_y = yield_speed_in::<M>(effective_modulus_pa, density_kg_m3, yield_pressure_pa)?;
        self.bent_by(RatioMap::thornton::<M>(v_y, self.ln_speed)?)
    }

    /// The envelope bent by the ratio map `map` ([`crate::ratio_map`]), checked at its corners.
    #[cfg(feature = "ratio_map")]
    #[inline(never)]
    pub fn bent_by(mut self, map: RatioMap) -> Result<Self, Error> {
        self.ratio_map = Some(map);
        // Every corner must give a peak force and duration that f32 carries, checked in log
        // space (`ln 1e-30 ..= ln 1e30`), so that no backend's `exp` is needed here.
        let (lo, hi) = (-69.077_55_f32, 69.077_55_f32);
        for (x, y) in self.corners() {
            let (lf, lt) = self.forward(x, y);
            if !(lo..=hi).contains(&lf) {
                return Err(Error::Unrepresentable("peak force"));
            }
            if !(lo..=hi).contains(&lt) {
                return Err(Error::Unrepresentable("contact duration"));
            }
        }
        Ok(self)
    }

    /// The ratio map, if the class has one and the kernel is built with the `ratio_map`
    /// feature (without it the bent paths compile away: a firmware whose scenes need no table
    /// carries none of them).
    #[inline(always)]
    fn bent(&self) -> Option<&RatioMap> {
        #[cfg(feature = "ratio_map")]
        return self.ratio_map.as_ref();
        #[cfg(not(feature = "ratio_map"))]
        None
    }

    /// The ratio map's values and slopes at `(x, y) = (ln R, ln u)`, or `None` for a Hertz
    /// envelope.
    pub fn local(&self, x: f32, y: f32) -> Option<Local> {
        self.bent().map(|m| m.local(m.s(x, y)))
    }

    /// `ln(8/5 / J)`: what a bent class's density at `(x, y) = (ln R, ln u)` adds to
    /// [`Envelope::ln_normalizer`] (0 for a Hertz envelope).
    pub fn ln_density_excess<M: Backend>(&self, x: f32, y: f32) -> f32 {
        match self.bent() {
            Some(map) => ln_excess::<M>(map, x, y),
            None => 0.0,
        }
    }

    /// Whether [`Envelope::ln_density_excess`] changes along `ln R` at a fixed `ln u` (a map
    /// whose direction has a radius part; not Thornton's, along `ln u` alone).
    pub fn excess_varies_with_radius(&self) -> bool {
        self.bent().is_some_and(|m| m.direction().0 != 0.0)
    }

    /// The measurement noise `(sigma_ln_force, sigma_ln_duration, cov_ln)` carried into this bent
    /// class's `(ln R, ln u)` at the point `(ln_force, ln_duration)` maps to, and the same
    /// widened by a chain's spread `chain` ([`NoiseXy::through`], [`NoiseXy::with_chain`]);
    /// `None` for a Hertz envelope (the caller's [`NoiseXy::new`] holds).
    #[inline(never)]
    pub fn bent_noise<M: Backend>(
        &self,
        (ln_force, ln_duration): (f32, f32),
        (sigma_ln_force, sigma_ln_duration, cov_ln): (f32, f32, f32),
        chain: &ChainSpread,
    ) -> Option<(NoiseXy, NoiseXy)> {
        let map = self.bent()?;
        let a = ln_force - self.ln_force_coeff;
        let b = ln_duration - self.ln_duration_coeff;
        let l = map.local(map.invert(a, b).2);
        let noise = NoiseXy::through::<M>(sigma_ln_force, sigma_ln_duration, cov_ln, l);
        Some((noise, noise.with_chain::<M>(chain, (l.dx, l.dy))))
    }

    /// `(ln F_max, ln t_c)` of radius `e^x` m and speed `e^y` m/s; a bent class adds
    /// `(phi_F(s), phi_t(s))` at `s = a x + b y`.
    pub fn forward(&self, x: f32, y: f32) -> (f32, f32) {
        if let Some(map) = self.bent() {
            return self.forward_bent(map, x, y);
        }
        (
            self.ln_force_coeff + 2.0 * x + 1.2 * y,
            self.ln_duration_coeff + x - 0.2 * y,
        )
    }

    /// `(ln R, ln u)` that gives `(ln F_max, ln t_c)` (the exact inverse of [`Self::forward`]).
    /// For a bent class `s` solves `h(s) = p A + q B` on the map ([`RatioMap::invert`]).
    pub fn invert_ln(&self, ln_force: f32, ln_duration: f32) -> (f32, f32) {
        if let Some(map) = self.bent() {
            return self.invert_bent(map, ln_force, ln_duration);
        }
        let a = ln_force - self.ln_force_coeff;
        let b = ln_duration - self.ln_duration_coeff;
        let y = (a - 2.0 * b) / JACOBIAN;
        (b + 0.2 * y, y)
    }

    /// [`Envelope::forward`] of a bent class (out of line: a scene without tables carries
    /// one copy, not one per caller).
    #[inline(never)]
    fn forward_bent(&self, map: &RatioMap, x: f32, y: f32) -> (f32, f32) {
        let (pf, pt) = map.forward(x, y);
        (
            self.ln_force_coeff + 2.0 * x + 1.2 * y + pf,
            self.ln_duration_coeff + x - 0.2 * y + pt,
        )
    }

    /// [`Envelope::invert_ln`] of a bent class (out of line, as [`Envelope::forward_bent`]).
    #[inline(never)]
    fn invert_bent(&self, map: &RatioMap, ln_force: f32, ln_duration: f32) -> (f32, f32) {
        let (x, y, _) = map.invert(
            ln_force - self.ln_force_coeff,
            ln_duration - self.ln_duration_coeff,
        );
        (x, y)
    }

    /// The radius and speed this class needs for a pulse of `peak_force_n` and `duration_s`,
    /// and where they lie against the class's ranges.
    pub fn invert<M: Backend>(&self, peak_force_n: f32, duration_s: f32) -> Inverted {
        let (x, y) = self.invert_ln(M::ln(peak_force_n), M::ln(duration_s));
        Inverted {
            radius_m: M::exp(x),
            speed_m_s: M::exp(y),
            radius_side: side(x, self.ln_radius),
            speed_side: side(y, self.ln_speed),
        }
    }

    /// The four corners `(ln R, ln u)` of the class's box.
    pub fn corners(&self) -> [(f32, f32); 4] {
        let (x0, x1) = self.ln_radius;
        let (y0, y1) = self.ln_speed;
        [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    }

    /// Prior density of `ln u` at `y` (zero outside the range):
    /// `beta e^(beta (y - y1)) / (1 - e^(beta (y0 - y1)))`, or `1 / (y1 - y0)` for `beta = 0`.
    pub fn speed_density<M: Backend>(&self, y: f32) -> f32 {
        let (y0, y1) = self.ln_speed;
        if !(y0..=y1).contains(&y) {
            return 0.0;
        }
        let b = self.speed_beta;
        if b.abs() < 1e-6 {
            return 1.0 / (y1 - y0);
        }
        b * M::exp(b * (y - y1)) / (1.0 - M::exp(b * (y0 - y1)))
    }

    /// Noiseless prior density of the class at `(ln F_max, ln t_c)`:
    /// `p(x) p(y) / 1.6` with `p(x) = 1 / (x1 - x0)` inside the box, 0 outside (`/ J` for
    /// a bent class).
    pub fn density<M: Backend>(&self, ln_force: f32, ln_duration: f32) -> f32 {
        let (x, y) = self.invert_ln(ln_force, ln_duration);
        let (x0, x1) = self.ln_radius;
        if !(x0..=x1).contains(&x) {
            return 0.0;
        }
        let jacobian = self.local(x, y).map_or(JACOBIAN, |l| l.jacobian);
        self.speed_density::<M>(y) / (x1 - x0) / jacobian
    }

    /// Log-likelihood of a noisy observation `(ln F_max, ln t_c)`: the class density
    /// convolved with the noise, the noise taken as independent in `(x, y)` ([`NoiseXy`]):
    ///
    /// `L = [Phi((x - x0)/sx) - Phi((x - x1)/sx)] / (x1 - x0) / 1.6
    ///      * beta e^(beta (y - y1) + beta^2 sy^2 / 2) / (1 - e^(beta (y0 - y1)))
    ///      * [Phi((y1 - y - beta sy^2)/sy) - Phi((y0 - y - beta sy^2)/sy)]`
    ///
    /// (the constant factors are [`Envelope::ln_normalizer`]; a bent class has its local
    /// Jacobian in place of 1.6, and its `noise` from [`Envelope::bent_noise`]). `-inf` when the
    /// observation is so far outside that f32 rounds the likelihood to zero.
    pub fn ln_likelihood<M: Backend>(
        &self,
        ln_force: f32,
        ln_duration: f32,
        noise: NoiseXy,
    ) -> f32 {
        let (x, y) = self.invert_ln(ln_force, ln_duration);
        let (sx, sy) = (noise.sigma_x, noise.sigma_y);
        let (x0, x1) = self.ln_radius;
        let (y0, y1) = self.ln_speed;
        let ix = math::normal_interval((x - x1) / sx, (x - x0) / sx);
        let b = self.speed_beta;
        let shift = b * sy * sy;
        let iy = math::normal_interval((y0 - y - shift) / sy, (y1 - y - shift) / sy);
        if ix <= 0.0 || iy <= 0.0 {
            return f32::NEG_INFINITY;
        }
        let ll = M::ln(ix * iy) + self.ln_normalizer + b * y + 0.5 * b * shift;
        if self.bent().is_some() {
            ll + self.ln_density_excess::<M>(x, y)
        } else {
            ll
        }
    }

    /// Squared standardised distance of an observation outside the class's box:
    /// `dx^2 + dy^2` with `dx` the distance of `x = ln R` outside `[x0, x1]` in units of
    /// `sigma_x` (0 inside), likewise `dy`.
    pub fn outside_sigmas_squared(&self, ln_force: f32, ln_duration: f32, noise: NoiseXy) -> f32 {
        let (x, y) = self.invert_ln(ln_force, ln_duration);
        let dx = outside(x, self.ln_radius) / noise.sigma_x;
        let dy = outside(y, self.ln_speed) / noise.sigma_y;
        dx * dx + dy * dy
    }
}

/// `ln(8/5 / J)` of a ratio map at `(x, y)` (out of line, as [`Envelope::forward_bent`]).
#[inline(never)]
fn ln_excess<M: Backend>(map: &RatioMap, x: f32, y: f32) -> f32 {
    M::ln(JACOBIAN / map.local(map.s(x, y)).jacobian)
}

/// `MIN_SIGMA` for NaN or tiny values, at most [`MAX_SIGMA`].
fn clamp_sigma(s: f32) -> f32 {
    if s >= MIN_SIGMA {
        s.min(MAX_SIGMA)
    } else {
        MIN_SIGMA
    }
}

/// Distance of `v` outside `[lo, hi]` (0 inside).
fn outside(v: f32, (lo, hi): (f32, f32)) -> f32 {
    if v < lo {
        lo - v
    } else if v > hi {
        v - hi
    } else {
        0.0
    }
}

/// Where `v` lies against `[lo, hi]`.
fn side(v: f32, (lo, hi): (f32, f32)) -> Side {
    if v < lo {
        Side::Below
    } else if v > hi {
        Side::Above
    } else {
        Side::Inside
    }
}
