//! Forward-mode dual numbers for the algorithmic tangents of the principal-space returns.
//!
//! A [`Dual<N>`] carries a value `v` and its gradient `d = ∂v/∂s` with respect to `N` seed
//! variables `s`. Every return algorithm of this crate is written once over the scalar
//! trait [`Real`]; evaluated with `f64` it is the plain algorithm, evaluated with
//! `Dual<N>` seeded on the trial principal strains (and, where needed, an internal
//! variable) it also yields the exact derivative of the algorithm, i.e. the consistent
//! (algorithmic) tangent of Simo & Taylor (1985), "Consistent tangent operators for
//! rate-independent elastoplasticity", CMAME 48:101–118, doi:10.1016/0045-7825(85)90070-2,
//! without hand-derived, region-by-region formulas that can drift from the algorithm.
//!
//! Branching (region selection, sorting) is decided on the values only, so the derivative
//! is that of the branch actually taken — exactly what Newton's method needs.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// The scalar operations the return algorithms use.
pub trait Real:
    Copy
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// A constant (zero gradient).
    fn cst(x: f64) -> Self;
    /// The value.
    fn re(self) -> f64;
    /// `√x`.
    fn sqrt(self) -> Self;
    /// `eˣ`.
    fn exp(self) -> Self;
    /// `ln x`.
    fn ln(self) -> Self;
    /// `sin x`.
    fn sin(self) -> Self;
    /// `cos x`.
    fn cos(self) -> Self;
}

impl Real for f64 {
    fn cst(x: f64) -> Self {
        x
    }
    fn re(self) -> f64 {
        self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn exp(self) -> Self {
        f64::exp(self)
    }
    fn ln(self) -> Self {
        f64::ln(self)
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
}

/// A value with its gradient with respect to `N` seed variables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual<const N: usize> {
    /// Value.
    pub v: f64,
    /// Gradient `∂v/∂s_k`.
    pub d: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// The seed variable number `k` with value `v` (gradient `e_k`).
    pub fn seed(v: f64, k: usize) -> Self {
        let mut d = [0.0; N];
        d[k] = 1.0;
        Self { v, d }
    }

    /// Chain rule for a scalar function with value `f` and derivative `df` at `self.v`.
    #[inline]
    fn chain(self, f: f64, df: f64) -> Self {
        let mut d = self.d;
        for x in &mut d {
            *x *= df;
        }
        Self { v: f, d }
    }
}

impl<const N: usize> Real for Dual<N> {
    fn cst(x: f64) -> Self {
        Self { v: x, d: [0.0; N] }
    }
    fn re(self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s)
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    fn ln(self) -> Self {
        self.chain(self.v.ln(), 1.0 / self.v)
    }
    fn sin(self) -> Self {
        self.chain(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Self {
        self.chain(self.v.cos(), -self.v.sin())
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for k in 0..N {
            self.d[k] += o.d[k];
        }
        self
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for k in 0..N {
            self.d[k] -= o.d[k];
        }
        self
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; N];
        for k in 0..N {
            d[k] = self.d[k] * o.v + self.v * o.d[k];
        }
        Self { v: self.v * o.v, d }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.v;
        let v = self.v * inv;
        let mut d = [0.0; N];
        for k in 0..N {
            d[k] = (self.d[k] - v * o.d[k]) * inv;
        }
        Self { v, d }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.chain(-self.v, -1.0)
    }
}

impl<const N: usize> Add<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: f64) -> Self {
        self.v += o;
        self
    }
}

impl<const N: usize> Sub<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: f64) -> Self {
        self.v -= o;
        self
    }
}

impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: f64) -> Self {
        self.chain(self.v * o, o)
    }
}

impl<const N: usize> Div<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        self.chain(self.v / o, 1.0 / o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_a_composite_function() {
        // f(x, y) = sqrt(x) exp(y) / (1 + x y) − sin(x) cos(y) + ln(x)
        let f =
            |x: Dual<2>, y: Dual<2>| x.sqrt() * y.exp() / (x * y + 1.0) - x.sin() * y.cos() + x.ln() * 2.0 - (-y) / 3.0;
        let (x0, y0) = (1.3, 0.4);
        let r = f(Dual::seed(x0, 0), Dual::seed(y0, 1));
        let h = 1e-6;
        let g = |x: f64, y: f64| f(Dual::cst(x), Dual::cst(y)).v;
        let fx = (g(x0 + h, y0) - g(x0 - h, y0)) / (2.0 * h);
        let fy = (g(x0, y0 + h) - g(x0, y0 - h)) / (2.0 * h);
        println!("dual: df/dx {:.12} vs FD {fx:.12}; df/dy {:.12} vs FD {fy:.12}", r.d[0], r.d[1]);
        assert!((r.d[0] - fx).abs() < 1e-8 && (r.d[1] - fy).abs() < 1e-8);
    }
}
