//! The event search of an accepted step: the earliest sign change of the contact end, the
//! kink, the turn and the clamp's switching function on the step's continuous output.

use crate::physics::events::{Enclosure, Poly, earliest_root, earliest_root_within};
use crate::physics::integrate::dense::Segment;
use crate::physics::laws::ForceLaw;

/// What a step contains.
pub(super) enum Event {
    /// Contact end at this theta.
    End(f64),
    /// Kink crossing at this theta.
    Kink(f64),
    /// The penetration turns (`delta' = 0`) at this theta; only for a law that
    /// [`ForceLaw::awaits_turn`].
    Turn(f64),
    /// The unclamped force changes sign (the clamp at zero engages or releases) at this theta.
    Clamp(f64),
    /// The step left the kink and returned across it: retry with a smaller step.
    Retry,
}

/// The clamp's switching function on the scaled state: [`ForceLaw::clamp_switch`] at
/// `delta = x delta_max`, `delta' = v u`.
pub(super) struct ClampSwitch {
    pub(super) law: ForceLaw,
    pub(super) d_m: f64,
    pub(super) u_m_s: f64,
}

impl ClampSwitch {
    pub(super) fn value(&self, y: [f64; 2]) -> f64 {
        self.law.clamp_switch(y[0] * self.d_m, y[1] * self.u_m_s)
    }

    /// No root where the law's bound over the box of `(x, v)` excludes zero.
    pub(super) fn enclosure(&self, x: (f64, f64), v: (f64, f64)) -> Enclosure {
        let (lo, hi) = self.law.clamp_switch_bounds(
            (x.0 * self.d_m, x.1 * self.d_m),
            (v.0 * self.u_m_s, v.1 * self.u_m_s),
        );
        if lo > 0.0 || hi < 0.0 {
            Enclosure::NoRoot
        } else {
            Enclosure::Unknown
        }
    }
}

/// Roots closer than this (in theta) to the start of a step are the restart itself.
pub(super) const RESTART_THETA: f64 = 1e-9;

/// Searches an accepted step for the earliest event, on every sign change of `x` (contact
/// end), of `x - x_d` (Adams kink) and of the clamp's switching function (while
/// `clamp_budget > 0`, with at most `clamp_splits` halvings), see [`crate::physics::events`].
/// The clamp is searched only up to the
/// earlier of the end and the kink.
pub(super) fn find_event(
    seg: &Segment,
    x_kink: Option<f64>,
    ends: (f64, bool),
    clamp: Option<&ClampSwitch>,
    (clamp_budget, clamp_splits): (usize, usize),
) -> Option<Event> {
    let (x_end, await_turn) = ends;
    // Most steps: no clamp to search, and the nested form's bound keeps every polynomial
    // switching function off zero, without the power-basis polynomials.
    if clamp.is_none()
        && seg.keeps_sign(0, x_end)
        && x_kink.is_none_or(|xk| seg.keeps_sign(0, xk))
        && (!await_turn || seg.keeps_sign(1, 0.0))
    {
        return None;
    }
    let x = seg.poly(0);
    // The cheap sign bound first: most steps keep every polynomial switching function away
    // from zero, and the search would find no root there either.
    let poly_root = |p: Poly, a: f64| {
        if p.keeps_sign_on_unit() {
            return None;
        }
        earliest_root(&|th| p.eval(th), &|lo, hi| p.enclosure(lo, hi), a, 1.0)
    };
    // At first contact x(0) = 0: that root is the start, not an end.
    let x_rel = x.minus(x_end);
    let end = poly_root(
        x_rel,
        if x_rel.c[0] == 0.0 {
            RESTART_THETA
        } else {
            0.0
        },
    );
    let turn = if await_turn {
        let v = seg.poly(1);
        poly_root(v, if v.c[0] == 0.0 { RESTART_THETA } else { 0.0 })
    } else {
        None
    };
    let mut kink = None;
    if let Some(xk) = x_kink {
        let g = x.minus(xk);
        if g.c[0] == 0.0 {
            // Restarted on the kink: a return across it inside this step needs a smaller step.
            if poly_root(g, RESTART_THETA).is_some() {
                return Some(Event::Retry);
            }
        } else {
            kink = poly_root(g, 0.0);
        }
    }
    let first = [end, kink, turn]
        .into_iter()
        .flatten()
        .fold(None, |acc: Option<f64>, th| {
            Some(acc.map_or(th, |a| a.min(th)))
        });
    let hi = first.unwrap_or(1.0);
    let switch = clamp.filter(|_| clamp_budget > 0).and_then(|sw| {
        let v = seg.poly(1);
        earliest_root_within(
            &|th| sw.value([x.eval(th), v.eval(th)]),
            &|a, b| sw.enclosure(x.range(a, b), v.range(a, b)),
            RESTART_THETA,
            hi,
            clamp_splits,
        )
    });
    match (switch, first) {
        (Some(th), _) => Some(Event::Clamp(th)),
        (None, Some(th)) if end == Some(th) => Some(Event::End(th)),
        (None, Some(th)) if turn == Some(th) => Some(Event::Turn(th)),
        (None, Some(th)) => Some(Event::Kink(th)),
        (None, None) => None,
    }
}
