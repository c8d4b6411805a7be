//! Checks that the contact integrator finds every switch of the clamped Adams IMPACT force
//! (off when `k delta^1.5 + c(delta) delta'` falls to zero, on again just before separation),
//! against an independent piecewise reference integrated here.
//!
//! Run with `--nocapture` to see the measured figures.

use host_sim::hertz64::{HertzImpact64, Material64};
use host_sim::integrate::{ContactProblem, Limits, Method, Tolerance, integrate_contact};
use host_sim::laws::{ForceLaw, step_cubic};

/// Independent reference: fixed-step RK4 in SI units, one smooth piece at a time. The pieces
/// are the force phase (on: `F = k delta^1.5 + c(delta) delta'` unclamped; off: `F = 0`) and
/// the side of the STEP ramp (`delta < d`: `c = STEP(delta, 0, 0, d, c_max)` written as its
/// cubic; `delta >= d`: `c = c_max`). Inside a piece the right-hand side is that piece's
/// smooth formula; a step that crosses a switch (`G` = 0, `delta = d` or `delta = 0`) is
/// shortened by bisection on its length until the switch is bracketed to 1e-15 of the
/// contact time, and the integration goes on from just past it in the new piece.
mod reference {
    use super::step_cubic;

    /// Steps per Hertz contact time.
    const STEPS_PER_TC: f64 = 100_000.0;

    /// An Adams IMPACT contact in SI units.
    pub struct Adams {
        /// `k` in N/m^1.5.
        pub k: f64,
        /// `c_max` in N s/m.
        pub c_max: f64,
        /// `d` in m.
        pub d: f64,
        /// Mass in kg.
        pub m: f64,
    }

    #[derive(Clone, Copy, PartialEq)]
    struct Piece {
        force_on: bool,
        below_d: bool,
    }

    impl Adams {
        /// The unclamped force `G` (N) with the damping of the given side of `d`.
        fn g(&self, y: [f64; 2], below_d: bool) -> f64 {
            let delta = y[0].max(0.0);
            let c = if below_d {
                let s = y[0] / self.d;
                self.c_max * s * s * (3.0 - 2.0 * s)
            } else {
                self.c_max
            };
            self.k * delta * delta.sqrt() + c * y[1]
        }

        fn rhs(&self, y: [f64; 2], p: Piece) -> [f64; 2] {
            let f = if p.force_on {
                self.g(y, p.below_d)
            } else {
                0.0
            };
            [y[1], -f / self.m]
        }

        fn rk4(&self, y: [f64; 2], h: f64, p: Piece) -> [f64; 2] {
            let add = |a: [f64; 2], s: f64, b: [f64; 2]| [a[0] + s * b[0], a[1] + s * b[1]];
            let k1 = self.rhs(y, p);
            let k2 = self.rhs(add(y, 0.5 * h, k1), p);
            let k3 = self.rhs(add(y, 0.5 * h, k2), p);
            let k4 = self.rhs(add(y, h, k3), p);
            [
                y[0] + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
                y[1] + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
            ]
        }

        /// Whether state `y` lies outside piece `p` or past the contact end; the true law's
        /// `G` (with `c` from `step_cubic`) decides the force phase.
        fn left(&self, y: [f64; 2], p: Piece) -> bool {
            let delta = y[0].max(0.0);
            let g = self.k * delta * delta.sqrt()
                + step_cubic(y[0], 0.0, 0.0, self.d, self.c_max) * y[1];
            y[0] <= 0.0 || (y[0] < self.d) != p.below_d || (g > 0.0) != p.force_on
        }

        /// `(contact duration s, rebound speed m/s, force switches)` of an impact at `u` m/s
        /// with Hertz contact time `t_c` s.
        pub fn impact(&self, u: f64, t_c: f64) -> (f64, f64, usize) {
            let h = t_c / STEPS_PER_TC;
            let (mut t, mut y) = (0.0, [0.0, u]);
            let mut p = Piece {
                force_on: true,
                below_d: true,
            };
            let mut switches = 0;
            while t < 10.0 * t_c {
                let y1 = self.rk4(y, h, p);
                if !self.left(y1, p) {
                    (t, y) = (t + h, y1);
                    continue;
                }
                let (mut lo, mut hi) = (0.0, h);
                while hi - lo > 1e-15 * t_c {
                    let mid = 0.5 * (lo + hi);
                    if self.left(self.rk4(y, mid, p), p) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                let y_hi = self.rk4(y, hi, p);
                if y_hi[0] <= 0.0 {
                    // Separation: land on delta = 0 with the piece's velocity.
                    let y_lo = self.rk4(y, lo, p);
                    let f = y_lo[0] / (y_lo[0] - y_hi[0]);
                    let v = y_lo[1] + f * (y_hi[1] - y_lo[1]);
                    return (t + lo + f * (hi - lo), -v, switches);
                }
                let next = Piece {
                    force_on: self.g(y_hi, y_hi[0] < self.d) > 0.0,
                    below_d: y_hi[0] < self.d,
                };
                switches += usize::from(next.force_on != p.force_on);
                (t, y, p) = (t + hi, y_hi, next);
            }
            panic!("reference: no separation within 10 contact times");
        }
    }
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// One Adams impact of the sweep: sphere material, radius (m), speed (m/s), `c_max` (N s/m).
struct Case {
    name: &'static str,
    hertz: HertzImpact64,
    c_max: f64,
}

/// Coal and sandstone on carbon steel, R = 0.015 ... 0.04 m, u = 1, 3, 5 m/s, c_max = 200,
/// 500, 1000 N s/m, d = 0.01 mm: 108 impacts.
fn sweep() -> Vec<Case> {
    let mut out = Vec::new();
    for (name, mat) in [
        ("coal", Material64::COAL),
        ("sandstone", Material64::SANDSTONE),
    ] {
        for r in [0.015, 0.02, 0.025, 0.03, 0.035, 0.04] {
            for u in [1.0, 3.0, 5.0] {
                for c_max in [200.0, 500.0, 1000.0] {
                    let hertz = HertzImpact64::new(&mat, &Material64::CARBON_STEEL, r, u)
                        .expect("valid scene");
                    out.push(Case { name, hertz, c_max });
                }
            }
        }
    }
    out
}

const D_M: f64 = 1e-5;

fn problem(c: &Case) -> ContactProblem {
    ContactProblem {
        law: ForceLaw::AdamsImpact {
            stiffness: c.hertz.stiffness,
            exponent: 1.5,
            c_max_n_s_m: c.c_max,
            d_m: D_M,
        },
        mass_kg: c.hertz.mass_kg,
        speed_m_s: c.hertz.speed_m_s,
        gravity_m_s2: 0.0,
    }
}

/// Every impact of the sweep: Dopri5 at rtol = atol = 1e-12 agrees with the piecewise
/// reference to 1e-9 in rebound speed and contact duration, including the impacts whose force
/// switches back on just before separation.
#[test]
fn adams_switches_match_a_piecewise_reference() {
    for method in [Method::Dopri5, Method::Dop853, Method::Rodas4, Method::Auto] {
        switches_match(method);
    }
}

/// [`adams_switches_match_a_piecewise_reference`] for one method at rtol 1e-12.
fn switches_match(method: Method) {
    let mut worst = [0.0_f64; 2];
    let mut wrong = 0;
    let mut switching_back_on = 0;
    for c in sweep() {
        let adams = reference::Adams {
            k: c.hertz.stiffness,
            c_max: c.c_max,
            d: D_M,
            m: c.hertz.mass_kg,
        };
        let (t_ref, v_ref, switches) = adams.impact(c.hertz.speed_m_s, c.hertz.duration_s);
        switching_back_on += usize::from(switches >= 2);
        let s = integrate_contact(
            &problem(&c),
            method,
            Tolerance::new(1e-12),
            &Limits::default(),
        )
        .expect("integrates");
        let errs = [rel(s.rebound_speed_m_s, v_ref), rel(s.duration_s, t_ref)];
        if errs.iter().any(|&e| e > 1e-9) {
            wrong += 1;
            eprintln!(
                "{method:?} {} R {} u {} c_max {}: {switches} switches, rebound err {:.1e}, t_c \
                 err {:.1e}",
                c.name, c.hertz.radius_m, c.hertz.speed_m_s, c.c_max, errs[0], errs[1]
            );
        }
        worst = [worst[0].max(errs[0]), worst[1].max(errs[1])];
    }
    eprintln!(
        "{method:?}: {wrong} of 108 beyond 1e-9 ({switching_back_on} switch back on); worst \
         rebound {:.1e}, t_c {:.1e}",
        worst[0], worst[1]
    );
    assert!(
        switching_back_on > 0,
        "the sweep must contain a switch back on"
    );
    assert_eq!(wrong, 0, "{method:?}");
}
