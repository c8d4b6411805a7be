//! The ratio table of a class whose contact law has a fixed damping coefficient (MSC Adams
//! IMPACT with a fixed `c_max`): the measured/Hertz ratios of the peak force and of the
//! duration, tabulated by the integrator over the class's damping ratio, that the kernel's
//! `coalshock::ratio_map::RatioMap` bends the class's envelope with.
//!
//! With `F = k delta^1.5 + c delta_dot`, the scaling `delta* = (m u^2 / k)^(2/5)`,
//! `t* = delta*/u` gives `delta'' = -delta^1.5 - Lambda delta'` with
//! `Lambda = c t* / m = c delta* / (m u)`. For a sphere `m = 4/3 pi rho R^3` and
//! `k = 4/3 E* sqrt(R)`, so `delta* ~ R u^(4/5)` and `ln Lambda = const - 2 ln R - ln u / 5`:
//! while the ramp depth `d` is small against `delta*`, the ratios are functions of
//! `s = -2 ln R - ln u / 5` alone. The table holds them at [`POINTS`] equally spaced `s` over
//! the class's box, each integrated on the line of the box's central `ln delta* = ln R +
//! 4/5 ln u` (the ramp's share `d / delta*` of the box's middle); [`class_residual`] measures
//! what the rest of the box leaves (the ramp's share `d / delta_max` varies from 0.02 to 0.19
//! over the paper's box).

use coalshock::ratio_map::{POINTS, RatioMap};

use crate::bridge::calibrate::{PulseRatios, pulse_ratios};
use crate::physics::impact::ImpactSpec;
use crate::physics::integrate::SimError;
use crate::physics::law_spec::LawSpec;
use crate::scene::SceneFile;

/// `(a, b)` of `s = a ln R + b ln u`: `ln Lambda` up to a constant.
pub const DIRECTION: (f64, f64) = (-2.0, -0.2);

/// The ratio table of one class (f64): `ln(F/F_Hertz)` and `ln(t_c/t_Hertz)` (the duration
/// from the area, as the kernel's detector reads it) at `POINTS` equally spaced `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RatioTable64 {
    /// `s` of the first and last points.
    pub s_range: (f64, f64),
    /// `ln(F_max / F_Hertz)` at each point.
    pub ln_force: [f64; POINTS],
    /// `ln(t_c / t_Hertz)` at each point.
    pub ln_duration: [f64; POINTS],
}

/// Whether `scene`'s law needs a ratio table per class: an Adams law, with a fixed `c_max`
/// or one solved per impact for a restitution (its damping ramps in over a fixed penetration
/// `d`, so the ratios change with `delta_max / d`, that is with size and speed); every other
/// law is calibrated once per scene (its ratios are the same for every impact).
pub fn needs_tables(scene: &SceneFile) -> bool {
    matches!(
        scene.contact,
        LawSpec::Adams { .. } | LawSpec::AdamsRestitution { .. }
    )
}

/// `s` of `(ln R, ln u)`.
fn s_of(x: f64, y: f64) -> f64 {
    DIRECTION.0 * x + DIRECTION.1 * y
}

/// The ratios of class `class` of `scene` at radius `radius_m` (m) and speed `speed_m_s`
/// (m/s), from the integrator ([`pulse_ratios`]).
pub fn direct(
    scene: &SceneFile,
    class: usize,
    radius_m: f64,
    speed_m_s: f64,
) -> Result<PulseRatios, SimError> {
    let c = &scene.classes[class];
    let mut spec = ImpactSpec::new(
        c.material.material(),
        scene.plate.material(),
        radius_m,
        speed_m_s,
    );
    spec.law = scene.class_law(class)?;
    pulse_ratios(&spec)
}

/// The class's box in `(x, y) = (ln R, ln u)`: `((x0, x1), (y0, y1))`.
fn ln_box(scene: &SceneFile, class: usize) -> ((f64, f64), (f64, f64)) {
    let c = &scene.classes[class];
    let u = c.speed_range_m_s();
    (
        (c.radius_m.min.ln(), c.radius_m.max.ln()),
        (u.min.ln(), u.max.ln()),
    )
}

/// The table of class `class` of `scene`: `s` from the smallest to the largest over the
/// class's box corners; at each `s` the point with `a x + b y = s` and
/// `x + 4/5 y = w_c` (the box's central `ln delta*`), integrated.
pub fn class_table(scene: &SceneFile, class: usize) -> Result<RatioTable64, SimError> {
    let ((x0, x1), (y0, y1)) = ln_box(scene, class);
    let corners = [(x0, y0), (x0, y1), (x1, y0), (x1, y1)].map(|(x, y)| s_of(x, y));
    let s_lo = corners.iter().copied().fold(f64::INFINITY, f64::min);
    let s_hi = corners.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let w_c = 0.5 * (x0 + x1) + 0.4 * (y0 + y1);
    let (a, b) = DIRECTION;
    // a x + b y = s, x + 0.8 y = w: det = 0.8 a - b.
    let det = 0.8 * a - b;
    let mut table = RatioTable64 {
        s_range: (s_lo, s_hi),
        ln_force: [0.0; POINTS],
        ln_duration: [0.0; POINTS],
    };
    for k in 0..POINTS {
        let s = s_lo + (s_hi - s_lo) * k as f64 / (POINTS - 1) as f64;
        let x = (0.8 * s - b * w_c) / det;
        let y = (a * w_c - s) / det;
        let r = direct(scene, class, x.exp(), y.exp())?;
        table.ln_force[k] = r.force.ln();
        table.ln_duration[k] = r.duration.ln();
    }
    Ok(table)
}

impl RatioTable64 {
    /// `(ln F ratio, ln t_c ratio)` at `(ln R, ln u)`, linear between the points (the kernel's
    /// interpolation, in f64).
    pub fn at(&self, x: f64, y: f64) -> (f64, f64) {
        let (s0, s1) = self.s_range;
        let step = (s1 - s0) / (POINTS - 1) as f64;
        let t = (s_of(x, y) - s0) / step;
        let k = (t.max(0.0) as usize).min(POINTS - 2);
        let w = t - k as f64;
        let lerp = |v: &[f64; POINTS]| v[k] + w * (v[k + 1] - v[k]);
        (lerp(&self.ln_force), lerp(&self.ln_duration))
    }

    /// The kernel's map of this table (f32); a table the kernel refuses is its typed error.
    pub fn to_kernel(&self) -> Result<RatioMap, coalshock::Error> {
        let f32s = |v: &[f64; POINTS]| v.map(|x| x as f32);
        RatioMap::new(
            (DIRECTION.0 as f32, DIRECTION.1 as f32),
            (self.s_range.0 as f32, self.s_range.1 as f32),
            f32s(&self.ln_force),
            f32s(&self.ln_duration),
        )
    }
}

/// The root mean square of `ln ratio - table` of the peak force and of the duration of class
/// `class` over a 4 x 4 grid of its box off the table's line (radius and speed at 1/8, 3/8,
/// 5/8, 7/8 of their log and linear ranges), against direct integration: the standard
/// deviation of what the table leaves, over the class's box.
pub fn class_residual(
    scene: &SceneFile,
    class: usize,
    table: &RatioTable64,
) -> Result<(f64, f64), SimError> {
    let ((x0, x1), _) = ln_box(scene, class);
    let u = scene.classes[class].speed_range_m_s();
    let (mut wf, mut wt) = (0.0f64, 0.0f64);
    for i in 0..4 {
        for j in 0..4 {
            let x = x0 + (x1 - x0) * (2 * i + 1) as f64 / 8.0;
            let speed = u.min + (u.max - u.min) * (2 * j + 1) as f64 / 8.0;
            let r = direct(scene, class, x.exp(), speed)?;
            let (tf, tt) = table.at(x, speed.ln());
            wf += (r.force.ln() - tf).powi(2);
            wt += (r.duration.ln() - tt).powi(2);
        }
    }
    Ok(((wf / 16.0).sqrt(), (wt / 16.0).sqrt()))
}
