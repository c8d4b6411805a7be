//! The Hertz pulse's shape as the detector reads it: its area and energy over `F_max t_c`,
//! its curvature at the peak, and the fit of a sampled pulse's peak and duration from its
//! largest sample, that sample's neighbours and the sum of its samples.

use crate::math::{self, Backend};

/// Area of the Hertz pulse over `F_max t_c`: `C_AREA = 1.6 / 2.9432752 = 0.5436104` (the
/// impulse `2 m u` over `F_max t_c`).
pub const C_AREA: f32 = 0.543_612_1;

/// Energy `integral F^2 dt` of the Hertz pulse over `F_max^2 t_c`:
/// `C_ENERGY = 2 B(8/5, 1/2) / (2.5 * 2.9432752) = 0.4113417`.
pub const C_ENERGY: f32 = 0.411_341_7;

/// Phase rate of `z = F^(2/3)` at the peak, in rad per `t_c`: the Hertz pulse bends there like
/// `cos(PEAK_OMEGA t / t_c)`, with `PEAK_OMEGA = sqrt(5/4) 2.9432752` (from `z'' = -(5/4) z`
/// at the peak, in the units `delta_max / u` where `t_c = 2.9432752`): 4.7 % faster than the
/// `pi` of a sine.
pub const PEAK_OMEGA: f32 = 3.290_681;

/// Peak (counts) and duration (samples) of a sampled Hertz pulse from its largest sample
/// `y0`, the samples before and after it and the sum of all its samples; `None` when they are
/// not a positive pulse.
pub fn shape_fit<M: Backend>(y0: f32, before: f32, after: f32, sum: f32) -> Option<(f32, f32)> {
    if !(y0 > 0.0 && sum > 0.0 && y0.is_finite() && sum.is_finite()) {
        return None;
    }
    let z = |y: f32| if y > 0.0 { M::pow_2_3(y) } else { 0.0 };
    let (z0, za, zb) = (z(y0), z(before.min(y0)), z(after.min(y0)));
    let mut peak = y0;
    let mut duration = sum / (C_AREA * peak);
    for _ in 0..3 {
        // Phase step per sample; a pulse shorter than one sample is clamped to one.
        let d = (PEAK_OMEGA / duration).min(core::f32::consts::PI);
        let (sh, ch) = math::sin_cos(0.5 * d.min(core::f32::consts::FRAC_PI_2));
        let b_max = z0 / ch;
        let b = if d >= 0.3 {
            let (s, c) = math::sin_cos(d);
            let r = za.max(zb) / z0;
            let t = ((r - c) / s).max(0.0).min(sh / ch);
            z0 * M::sqrt(1.0 + t * t)
        } else {
            let curv = za - 2.0 * z0 + zb;
            if curv < 0.0 {
                let off = (za - zb) / (2.0 * curv);
                z0 - 0.25 * (za - zb) * off
            } else {
                z0
            }
        };
        peak = M::pow_3_2(b.max(z0).min(b_max));
        duration = sum / (C_AREA * peak);
    }
    if peak.is_finite() && duration.is_finite() && duration > 0.0 {
        Some((peak, duration))
    } else {
        None
    }
}
