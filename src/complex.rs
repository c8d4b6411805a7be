//! Complex numbers in f32: what the chain's transfer functions, their roots and their
//! frequency responses need (`+`, `-`, `*`, `/`, a scale, and `e^(i theta)`).

/// A complex number in f32.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct C {
    pub(crate) re: f32,
    pub(crate) im: f32,
}

impl C {
    pub(crate) const fn new(re: f32, im: f32) -> Self {
        Self { re, im }
    }
    pub(crate) fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    pub(crate) fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    pub(crate) fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    pub(crate) fn norm2(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    pub(crate) fn div(self, o: C) -> C {
        let d = o.norm2();
        C::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    pub(crate) fn scale(self, k: f32) -> C {
        C::new(self.re * k, self.im * k)
    }
}

/// `e^(i theta)` (`theta` in rad, any finite value): reduced to `[-pi, pi]`, then
/// [`crate::math::sin_cos`]. Not inlined: only a scene's build calls it.
#[inline(never)]
pub(crate) fn cis(theta: f32) -> C {
    use core::f32::consts::TAU;
    let r = theta - TAU * libm::floorf(theta / TAU + 0.5);
    let (sin, cos) = crate::math::sin_cos(r.abs());
    C::new(cos, if r < 0.0 { -sin } else { sin })
}
