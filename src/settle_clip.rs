//! The error that beam modes' sections, left off the chain's state by a clipped run, put
//! into that pulse's own samples after the run: read off the settle observer's fit
//! ([`crate::settle`]), so that the pulse is measured from its flanks (features
//! `pulse_shape` and `settle`).
//!
//! **Why.** While the ADC clips, the sections invert samples that are not the chain's
//! output. From the first equalised sample that no longer reads a clipped one (the
//! *anchor*: past the accelerometer FIR's delay, if there is one) the sections' input is
//! right again, and what is wrong is their state only: the equalised value is
//! `y_n = F_n + sum_i d_i phi_i(n)`, with `d` (two numbers per section) the state error at
//! the anchor and `phi_i` the sections' free response from the unit state `e_i`. Those are
//! the columns the observer fits after the pulse. Started at the anchor rather than at its
//! window, its shadows give, on the way to the window, the columns at the pulse's own
//! samples: the two after the run that the flank fit reads, and the sum of those the pulse
//! sums after the anchor.
//!
//! **What it states.** For a believed window ([`ClipError`]): `g_k . d` at those three
//! (counts), each with its variance `noise^2 |R^-T g_k|^2` from the fit's triangular factor
//! `R` (rows of unit weight, `noise` the equalised noise's RMS). A direction the window
//! cannot tell from the others leaves the error unknown: `None`.
//!
//! **Cost.** The shadows run from the anchor to the window's first sample, at most
//! [`MAX_TO_WINDOW`] samples (a pulse's tail: tens to a few thousand), once per clipped
//! pulse; 100 B more per [`crate::settle::Settler`] (an `Option<ClipColumns>`,
//! `tests/sizes.rs`).

use crate::equaliser::{EqualiserDesign, SECTION_STATES as UNKNOWNS, SectionStates};

/// Samples from the anchor to the window at most: a pulse that took longer to end is not
/// read (its columns would cost that many steps per unknown).
pub const MAX_TO_WINDOW: u32 = 1 << 15;

/// Where a clipped pulse waiting for the observer lies, counted from its anchor (the first
/// equalised sample past the run and the samples the FIR took from it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClipAnchor {
    /// Samples from the anchor to the window's first (the window's warm-up included after).
    pub to_window: u32,
    /// The pulse's samples from the anchor on (its sum takes them).
    pub in_pulse: u32,
}

/// The sections' state error in a clipped pulse's samples after the run (counts).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClipError {
    /// At the anchor and the sample after it (the flank fit's two samples after the run).
    pub after: [f32; 2],
    /// Summed over the pulse's samples from the anchor on.
    pub sum: f32,
    /// The variances of `after[0]`, `after[1]` and `sum` (counts^2).
    pub variance: [f32; 3],
}

/// The three functionals `g_k` (one column per unknown): the free responses at the anchor's
/// two samples and their sum over the pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClipColumns {
    g: [[f32; UNKNOWNS]; 3],
}

impl ClipColumns {
    /// Starts `shadows` at the unit states at the anchor and runs them with zero input to the
    /// window's first sample, keeping each one's output at the anchor's two samples and its
    /// sum over the pulse's. `None` past [`MAX_TO_WINDOW`] or with fewer than two samples
    /// after the anchor in the pulse.
    pub fn run_to_window(
        design: &EqualiserDesign,
        anchor: ClipAnchor,
        shadows: &mut [SectionStates; UNKNOWNS],
    ) -> Option<Self> {
        let unknowns = 2 * design.section_count();
        let ClipAnchor {
            to_window,
            in_pulse,
        } = anchor;
        if to_window > MAX_TO_WINDOW || in_pulse < 2 || in_pulse > to_window {
            return None;
        }
        let mut g = [[0.0; UNKNOWNS]; 3];
        for (i, shadow) in shadows.iter_mut().enumerate().take(unknowns) {
            *shadow = [[0.0; 2]; crate::equaliser::MAX_MODES];
            if let Some(s) = shadow.get_mut(i / 2).and_then(|st| st.get_mut(i % 2)) {
                *s = 1.0;
            }
            for n in 0..to_window {
                let x = design.free_step(shadow);
                let column = [n == 0, n == 1, n < in_pulse];
                for (gk, take) in g.iter_mut().zip(column) {
                    if let (true, Some(slot)) = (take, gk.get_mut(i)) {
                        *slot += x;
                    }
                }
            }
        }
        Some(Self { g })
    }

    /// The error at the three for the state error `d` at the anchor, with the variances
    /// `noise^2 |R^-T g_k|^2` from the fit's upper-triangular `r` (`None` when a column's
    /// diagonal is below `tolerance` of its column's norm, `norm2`).
    pub fn error(
        &self,
        d: &[f32; UNKNOWNS],
        r: &[[f32; UNKNOWNS + 1]; UNKNOWNS],
        (norm2, tolerance, unknowns): (&[f32; UNKNOWNS], f32, usize),
        noise: f32,
    ) -> Option<ClipError> {
        let mut value = [0.0; 3];
        let mut variance = [0.0; 3];
        for ((gk, v), var) in self.g.iter().zip(&mut value).zip(&mut variance) {
            *v = gk.iter().zip(d).take(unknowns).map(|(g, d)| g * d).sum();
            // Forward substitution of R^T w = g.
            let mut w = [0.0_f32; UNKNOWNS];
            for i in 0..unknowns {
                let mut acc = gk.get(i).copied().unwrap_or(0.0);
                for (j, wj) in w.iter().enumerate().take(i) {
                    acc -= r.get(j).and_then(|rj| rj.get(i)).copied().unwrap_or(0.0) * wj;
                }
                let diag = r.get(i).and_then(|ri| ri.get(i)).copied().unwrap_or(0.0);
                let norm = libm::sqrtf(norm2.get(i).copied().unwrap_or(0.0));
                // NaN is not told apart either.
                let told = diag.abs() > tolerance * norm;
                if !told {
                    return None;
                }
                if let Some(slot) = w.get_mut(i) {
                    *slot = acc / diag;
                }
            }
            *var = noise * noise * w.iter().map(|x| x * x).sum::<f32>();
        }
        let [a0, a1, sum] = value;
        (variance.iter().all(|v| v.is_finite()) && sum.is_finite()).then_some(ClipError {
            after: [a0, a1],
            sum,
            variance,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `g . d` and `noise^2 g^T (R^T R)^-1 g` against the closed form of an upper-triangular
    /// `R = [[2, 1], [0, 4]]`: `(R^T R)^-1 = R^-1 R^-T` with `R^-1 = [[1/2, -1/8], [0, 1/4]]`,
    /// so for `g = (1, 1)`, `R^-T g = (1/2, 1/8)` and the variance is `noise^2 (1/4 + 1/64)`.
    fn set<const C: usize>(m: &mut [[f32; C]], i: usize, j: usize, v: f32) {
        if let Some(x) = m.get_mut(i).and_then(|row| row.get_mut(j)) {
            *x = v;
        }
    }

    #[test]
    fn the_error_and_its_variance_match_the_closed_form() {
        let mut g = [[0.0; UNKNOWNS]; 3];
        for k in 0..3 {
            set(&mut g, k, 0, 1.0);
            set(&mut g, k, 1, 1.0);
        }
        let columns = ClipColumns { g };
        let mut r = [[0.0; UNKNOWNS + 1]; UNKNOWNS];
        set(&mut r, 0, 0, 2.0);
        set(&mut r, 0, 1, 1.0);
        set(&mut r, 1, 1, 4.0);
        let norm2 = [1.0; UNKNOWNS];
        let mut d = [[0.0; UNKNOWNS]];
        set(&mut d, 0, 0, 3.0);
        set(&mut d, 0, 1, -1.0);
        let [d] = d;
        let e = columns
            .error(&d, &r, (&norm2, 1e-4, 2), 2.0)
            .unwrap_or_else(|| unreachable!("a full-rank R states the error"));
        assert_eq!(e.after, [2.0, 2.0]);
        assert_eq!(e.sum, 2.0);
        let expected = 4.0 * (0.25 + 1.0 / 64.0);
        for v in e.variance {
            assert!((v - expected).abs() < 1e-6 * expected, "{v}");
        }
        // A direction the fit cannot tell from the others: no error is stated.
        set(&mut r, 1, 1, 0.0);
        assert!(columns.error(&d, &r, (&norm2, 1e-4, 2), 2.0).is_none());
    }
}
