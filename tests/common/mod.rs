//! Shared by the test files: the exact shape of an undamped Hertz impact, integrated here in
//! f64 from the equation of motion (independent of the kernel and its constants).
#![allow(dead_code)]

use std::sync::OnceLock;

/// The rising half of the normalised impact `y'' = -(5/4) y^(3/2)`, `y(0) = 0`, `y'(0) = 1`
/// (`y = delta / delta_max`, `s = t u / delta_max`; `(5/4)` because `k delta_max^(5/2) =
/// (5/4) m u^2`): `(h, s_peak, y, y')` on the grid `s = i h` up to the peak.
struct Shape {
    h: f64,
    s_peak: f64,
    y: Vec<f64>,
    dy: Vec<f64>,
}

fn shape() -> &'static Shape {
    static SHAPE: OnceLock<Shape> = OnceLock::new();
    SHAPE.get_or_init(|| {
        let h = 2e-5;
        let f = |y: f64, v: f64| (v, -1.25 * y.max(0.0).powf(1.5));
        let (mut y, mut v) = (0.0f64, 1.0f64);
        let (mut ys, mut dys) = (vec![y], vec![v]);
        loop {
            let (k1y, k1v) = f(y, v);
            let (k2y, k2v) = f(y + 0.5 * h * k1y, v + 0.5 * h * k1v);
            let (k3y, k3v) = f(y + 0.5 * h * k2y, v + 0.5 * h * k2v);
            let (k4y, k4v) = f(y + h * k3y, v + h * k3v);
            let (ny, nv) = (
                y + h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y),
                v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            );
            if nv <= 0.0 {
                // The peak lies between: y' is linear there to O(h^2), so interpolate.
                let frac = v / (v - nv);
                let s_peak = (ys.len() as f64 - 1.0 + frac) * h;
                return Shape {
                    h,
                    s_peak,
                    y: ys,
                    dy: dys,
                };
            }
            (y, v) = (ny, nv);
            ys.push(y);
            dys.push(v);
        }
    })
}

/// Contact duration of the normalised impact, `t_c u / delta_max` (the textbook constant
/// 2.9432752...), as integrated here.
pub fn contact_time_factor() -> f64 {
    2.0 * shape().s_peak
}

/// `F / F_max` of an undamped Hertz impact at `x = t / t_c`; 0 outside `[0, 1]`.
pub fn hertz_shape(x: f64) -> f64 {
    if !(0.0..=1.0).contains(&x) {
        return 0.0;
    }
    let sh = shape();
    // The pulse is symmetric about its peak.
    let s = (x.min(1.0 - x) * 2.0 * sh.s_peak).max(0.0);
    let i = ((s / sh.h) as usize).min(sh.y.len() - 1);
    let j = (i + 1).min(sh.y.len() - 1);
    let y = if i == j {
        // Between the last grid point and the peak: a parabola with the peak's y' = 0.
        let ds = s - i as f64 * sh.h;
        sh.y[i] + sh.dy[i] * ds * (1.0 - 0.5 * ds / (sh.s_peak - i as f64 * sh.h).max(1e-300))
    } else {
        // Cubic Hermite between grid points.
        let t = (s - i as f64 * sh.h) / sh.h;
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * sh.y[i]
            + (t3 - 2.0 * t2 + t) * sh.h * sh.dy[i]
            + (-2.0 * t3 + 3.0 * t2) * sh.y[j]
            + (t3 - t2) * sh.h * sh.dy[j]
    };
    y.max(0.0).powf(1.5)
}
