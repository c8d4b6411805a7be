//! Shared by the test files: a seeded generator, the moments of a sample of pairs, Simpson's rule, the textbook impact in f64, and the exact
//! shape of an undamped Hertz impact, integrated here in
//! f64 from the equation of motion (independent of the kernel and its constants).
#![allow(dead_code)]

use std::sync::OnceLock;

use coalshock::Material;

/// xorshift64* with Box-Muller normals: small, seeded, reproducible.
pub struct Rng {
    state: u64,
    spare: Option<f64>,
}

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1,
            spare: None,
        }
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.state;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.state = x;
        x.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let (a, b) = (self.uniform(), self.uniform());
        let r = (-2.0 * a.ln()).sqrt();
        let t = std::f64::consts::TAU * b;
        self.spare = Some(r * t.sin());
        r * t.cos()
    }
}

/// The textbook Hertz impact in f64: `(F_max in N, t_c in s)`.
pub fn hertz64(particle: &Material, plate: &Material, r: f64, u: f64) -> (f64, f64) {
    let c = |m: &Material| (1.0 - (m.poisson as f64).powi(2)) / m.modulus_pa as f64;
    let e = 1.0 / (c(particle) + c(plate));
    let m = particle.density_kg_m3 as f64 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let k = 4.0 / 3.0 * e * r.sqrt();
    let d = (5.0 * m * u * u / (4.0 * k)).powf(0.4);
    (k * d.powf(1.5), 2.943_275_184_324_7 * d / u)
}

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

/// One impact in sample units: starts at sample `start` (fractional), lasts `len` samples,
/// peaks at `amp` counts, of class `class`.
#[derive(Debug, Clone, Copy)]
pub struct Pulse {
    pub start: f64,
    pub len: f64,
    pub amp: f64,
    pub class: u8,
}

impl Pulse {
    /// The pulse's value at sample `i`.
    pub fn at(&self, i: usize) -> f64 {
        self.amp * hertz_shape((i as f64 - self.start) / self.len)
    }
    /// The first sample after the pulse.
    pub fn end(&self) -> usize {
        (self.start + self.len).ceil() as usize
    }
}

/// `int_0^1 f` by composite Simpson with `n` (even) panels.
pub fn simpson(f: impl Fn(f64) -> f64, n: usize) -> f64 {
    let h = 1.0 / n as f64;
    let mut acc = f(0.0) + f(1.0);
    for i in 1..n {
        acc += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
    }
    acc * h / 3.0
}

/// `(var x, var y, cov(x, y))` of paired draws (population moments, over `n`).
pub fn variances_and_covariance(xs: &[f64], ys: &[f64]) -> (f64, f64, f64) {
    let n = xs.len().min(ys.len()).max(1) as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let vx = xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>() / n;
    let vy = ys.iter().map(|y| (y - my).powi(2)).sum::<f64>() / n;
    let cxy = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / n;
    (vx, vy, cxy)
}
