//! Classical Runge-Kutta 4, one step, with the cubic Hermite interpolant as its continuous
//! output.

use crate::physics::integrate::dense::Segment;
use crate::physics::integrate::rhs::{Rhs, Trial, lin};

/// One classical RK4 step of size `h` from `(t, y)` with slope `k1`.
pub(super) fn rk4_step(rhs: &mut Rhs, t: f64, y: [f64; 2], k1: [f64; 2], h: f64) -> Trial {
    let k2 = rhs.f(lin(y, h, &[(0.5, k1)]));
    let k3 = rhs.f(lin(y, h, &[(0.5, k2)]));
    let k4 = rhs.f(lin(y, h, &[(1.0, k3)]));
    let y1 = lin(
        y,
        h,
        &[
            (1.0 / 6.0, k1),
            (1.0 / 3.0, k2),
            (1.0 / 3.0, k3),
            (1.0 / 6.0, k4),
        ],
    );
    let f1 = rhs.f(y1);
    Trial {
        y1,
        f1,
        force1_n: rhs.last_force_n,
        seg: Segment::hermite(t, h, y, k1, y1, f1),
        err: 0.0,
    }
}
