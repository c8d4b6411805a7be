//! The skewness the kernel's shape check reads of a pulse: the third standardised moment of
//! time, weighted by the signal squared, over the points above the detector's trigger.

/// `E[(t - mu)^3] / E[(t - mu)^2]^(3/2)` of the points `(t, v)` (any unit of time `t`, signal
/// `v` in any unit) weighted by `v^2`, two-pass; 0 when the weight or the variance is 0.
pub fn weighted_skewness(points: &[(f64, f64)]) -> f64 {
    let m0: f64 = points.iter().map(|p| p.1 * p.1).sum();
    if m0 <= 0.0 {
        return 0.0;
    }
    let moment = |k: i32, mu: f64| -> f64 {
        points
            .iter()
            .map(|p| (p.0 - mu).powi(k) * (p.1 * p.1))
            .sum::<f64>()
            / m0
    };
    let mu = moment(1, 0.0);
    let var = moment(2, mu);
    let third = moment(3, mu);
    if var > 0.0 {
        third / var.powf(1.5)
    } else {
        0.0
    }
}
