//! Dormand-Prince 5(4) (Hairer's `DOPRI5`): its tableau, error estimate and 4th-order
//! continuous extension, one step.

use crate::physics::integrate::Tolerance;
use crate::physics::integrate::dense::Segment;
use crate::physics::integrate::rhs::{Rhs, Trial, lin};

// Dormand-Prince 5(4) coefficients (Hairer, Norsett & Wanner, Table II.5.2) and the dense
// output coefficients of DOPRI5's CONTD5.
pub(super) const C2: f64 = 1.0 / 5.0;
pub(super) const C3: f64 = 3.0 / 10.0;
pub(super) const C4: f64 = 4.0 / 5.0;
pub(super) const C5: f64 = 8.0 / 9.0;
pub(super) const A21: f64 = 1.0 / 5.0;
pub(super) const A31: f64 = 3.0 / 40.0;
pub(super) const A32: f64 = 9.0 / 40.0;
pub(super) const A41: f64 = 44.0 / 45.0;
pub(super) const A42: f64 = -56.0 / 15.0;
pub(super) const A43: f64 = 32.0 / 9.0;
pub(super) const A51: f64 = 19372.0 / 6561.0;
pub(super) const A52: f64 = -25360.0 / 2187.0;
pub(super) const A53: f64 = 64448.0 / 6561.0;
pub(super) const A54: f64 = -212.0 / 729.0;
pub(super) const A61: f64 = 9017.0 / 3168.0;
pub(super) const A62: f64 = -355.0 / 33.0;
pub(super) const A63: f64 = 46732.0 / 5247.0;
pub(super) const A64: f64 = 49.0 / 176.0;
pub(super) const A65: f64 = -5103.0 / 18656.0;
pub(super) const A71: f64 = 35.0 / 384.0;
pub(super) const A73: f64 = 500.0 / 1113.0;
pub(super) const A74: f64 = 125.0 / 192.0;
pub(super) const A75: f64 = -2187.0 / 6784.0;
pub(super) const A76: f64 = 11.0 / 84.0;
pub(super) const E1: f64 = 71.0 / 57600.0;
pub(super) const E3: f64 = -71.0 / 16695.0;
pub(super) const E4: f64 = 71.0 / 1920.0;
pub(super) const E5: f64 = -17253.0 / 339200.0;
pub(super) const E6: f64 = 22.0 / 525.0;
pub(super) const E7: f64 = -1.0 / 40.0;
pub(super) const D1: f64 = -12715105075.0 / 11282082432.0;
pub(super) const D3: f64 = 87487479700.0 / 32700410799.0;
pub(super) const D4: f64 = -10690763975.0 / 1880347072.0;
pub(super) const D5: f64 = 701980252875.0 / 199316789632.0;
pub(super) const D6: f64 = -1453857185.0 / 822651844.0;
pub(super) const D7: f64 = 69997945.0 / 29380423.0;

pub(super) fn dopri_step(
    rhs: &mut Rhs,
    t: f64,
    y: [f64; 2],
    k1: [f64; 2],
    h: f64,
    tol: Tolerance,
) -> Trial {
    // The stage abscissae are implicit in the coefficients (autonomous system).
    let _ = (C2, C3, C4, C5);
    let k2 = rhs.f(lin(y, h, &[(A21, k1)]));
    let k3 = rhs.f(lin(y, h, &[(A31, k1), (A32, k2)]));
    let k4 = rhs.f(lin(y, h, &[(A41, k1), (A42, k2), (A43, k3)]));
    let k5 = rhs.f(lin(y, h, &[(A51, k1), (A52, k2), (A53, k3), (A54, k4)]));
    let k6 = rhs.f(lin(
        y,
        h,
        &[(A61, k1), (A62, k2), (A63, k3), (A64, k4), (A65, k5)],
    ));
    let y1 = lin(
        y,
        h,
        &[(A71, k1), (A73, k3), (A74, k4), (A75, k5), (A76, k6)],
    );
    let k7 = rhs.f(y1);
    let mut err2 = 0.0;
    let mut r = [[0.0; 5]; 2];
    for i in 0..2 {
        let e = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        let sk = tol.atol + tol.rtol * y[i].abs().max(y1[i].abs());
        err2 += (e / sk) * (e / sk);
        let ydiff = y1[i] - y[i];
        let bspl = h * k1[i] - ydiff;
        r[i] = [
            y[i],
            ydiff,
            bspl,
            ydiff - h * k7[i] - bspl,
            h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]),
        ];
    }
    Trial {
        y1,
        f1: k7,
        force1_n: rhs.last_force_n,
        seg: Segment::nested(t, h, r),
        err: (err2 / 2.0).sqrt(),
    }
}
