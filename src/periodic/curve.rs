//! The periodic curve: a truncated Fourier series in the normalised time θ = t/T ∈ [0, 1),
//! and the layout that maps its components onto the configuration (one curve per coordinate,
//! or one curve shared by all bodies of a choreography with time shifts T/N).

use crate::error::{GviError, Result};
use std::f64::consts::TAU;

/// Number of real basis functions of a Fourier series with K modes: 1 + 2K.
pub fn basis_len(modes: usize) -> usize {
    2 * modes + 1
}

/// The Fourier basis at θ: φ₀ = 1, φ_{2k−1} = cos 2πkθ, φ_{2k} = sin 2πkθ (k = 1…K),
/// with dφ/dθ into `d1` and d²φ/dθ² into `d2` (each of length 2K + 1).
pub fn basis_at(theta: f64, modes: usize, phi: &mut [f64], d1: &mut [f64], d2: &mut [f64]) {
    phi[0] = 1.0;
    d1[0] = 0.0;
    d2[0] = 0.0;
    for k in 1..=modes {
        let w = TAU * k as f64;
        let (s, c) = (w * theta).sin_cos();
        phi[2 * k - 1] = c;
        phi[2 * k] = s;
        d1[2 * k - 1] = -w * s;
        d1[2 * k] = w * c;
        d2[2 * k - 1] = -w * w * c;
        d2[2 * k] = -w * w * s;
    }
}

/// How the components of the unknown curve(s) make up the configuration q ∈ R^D.
///
/// Coordinate r of the configuration is component `component(r)` of the Fourier curve,
/// evaluated at θ + `shift(r)`.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// Every coordinate is its own curve (D components, no shifts): a general periodic orbit.
    Orbit {
        /// Configuration dimension D.
        dim: usize,
    },
    /// An N-body choreography: one curve x(t) ∈ R^k shared by all bodies,
    /// q_i(t) = x(t + iT/N), i.e. q_{i+1}(t) = q_i(t + T/N).
    Choreography {
        /// Number of bodies N.
        bodies: usize,
        /// Dimension k of each body.
        body_dim: usize,
    },
}

impl Layout {
    /// Configuration dimension D.
    pub fn dim(&self) -> usize {
        match *self {
            Layout::Orbit { dim } => dim,
            Layout::Choreography { bodies, body_dim } => bodies * body_dim,
        }
    }

    /// Number of components of the unknown curve (D for an orbit, k for a choreography).
    pub fn components(&self) -> usize {
        match *self {
            Layout::Orbit { dim } => dim,
            Layout::Choreography { body_dim, .. } => body_dim,
        }
    }

    /// The curve component that coordinate r follows.
    pub fn component(&self, r: usize) -> usize {
        match *self {
            Layout::Orbit { .. } => r,
            Layout::Choreography { body_dim, .. } => r % body_dim,
        }
    }

    /// The time shift (a fraction of the period) of coordinate r.
    pub fn shift(&self, r: usize) -> f64 {
        match *self {
            Layout::Orbit { .. } => 0.0,
            Layout::Choreography { bodies, body_dim } => (r / body_dim) as f64 / bodies as f64,
        }
    }

    /// The distinct shifts, and for each coordinate the index of its shift.
    pub(crate) fn shift_classes(&self) -> (Vec<f64>, Vec<usize>) {
        match *self {
            Layout::Orbit { dim } => (vec![0.0], vec![0; dim]),
            Layout::Choreography { bodies, body_dim } => (
                (0..bodies).map(|i| i as f64 / bodies as f64).collect(),
                (0..bodies * body_dim).map(|r| r / body_dim).collect(),
            ),
        }
    }
}

/// A periodic curve q(t) = a₀ + Σ_{k=1..K} (a_k cos 2πkt/T + b_k sin 2πkt/T) with its layout.
///
/// Coefficients are stored basis-function-major: entry `m * components + c` is the coefficient
/// of basis function m (0: a₀, 2k−1: a_k, 2k: b_k) in component c.
#[derive(Debug, Clone, PartialEq)]
pub struct FourierCurve {
    /// Number of modes K.
    pub modes: usize,
    /// How components map to coordinates.
    pub layout: Layout,
    /// The coefficients, (2K + 1) × components, basis-function-major.
    pub coefficients: Vec<f64>,
    /// The period T.
    pub period: f64,
}

impl FourierCurve {
    /// The zero curve with K ≥ 1 modes and period T > 0.
    pub fn zeros(modes: usize, layout: Layout, period: f64) -> Result<Self> {
        if modes < 1 {
            return Err(GviError::InvalidInput {
                name: "modes".into(),
                reason: format!(
                    "a periodic curve needs at least one mode (K >= 1), got K = {modes}"
                ),
            });
        }
        if !(period.is_finite() && period > 0.0) {
            return Err(GviError::InvalidParameter {
                name: "period".into(),
                value: period,
                reason: "the period must be finite and positive".into(),
            });
        }
        let len = basis_len(modes) * layout.components();
        Ok(FourierCurve {
            modes,
            layout,
            coefficients: vec![0.0; len],
            period,
        })
    }

    /// Set mode k's cosine (`a`) and sine (`b`) coefficients for every component
    /// (k = 0: only `a`, the mean).
    pub fn set_mode(&mut self, k: usize, a: &[f64], b: &[f64]) -> Result<()> {
        let nc = self.layout.components();
        if k > self.modes {
            return Err(GviError::InvalidInput {
                name: "modes".into(),
                reason: format!(
                    "too few modes: the guess sets mode {k} but the curve has only K = {} modes",
                    self.modes
                ),
            });
        }
        crate::error::ensure_len("guess coefficients a", nc, a.len())?;
        crate::error::ensure_finite("guess coefficients", a)?;
        crate::error::ensure_finite("guess coefficients", b)?;
        if k == 0 {
            if !b.is_empty() {
                return Err(GviError::InvalidInput {
                    name: "guess".into(),
                    reason: "mode 0 (the mean) has no sine coefficients b".into(),
                });
            }
            self.coefficients[..nc].copy_from_slice(a);
        } else {
            crate::error::ensure_len("guess coefficients b", nc, b.len())?;
            self.coefficients[(2 * k - 1) * nc..2 * k * nc].copy_from_slice(a);
            self.coefficients[2 * k * nc..(2 * k + 1) * nc].copy_from_slice(b);
        }
        Ok(())
    }

    /// The same curve with K' modes: extra modes zero, or the tail dropped.
    pub fn with_modes(&self, modes: usize) -> Result<Self> {
        let mut c = FourierCurve::zeros(modes, self.layout.clone(), self.period)?;
        let n = c.coefficients.len().min(self.coefficients.len());
        c.coefficients[..n].copy_from_slice(&self.coefficients[..n]);
        Ok(c)
    }

    /// The size max_c (|a_k,c|, |b_k,c|) of mode k.
    pub fn mode_size(&self, k: usize) -> f64 {
        let nc = self.layout.components();
        let range = if k == 0 {
            0..nc
        } else {
            (2 * k - 1) * nc..(2 * k + 1) * nc
        };
        self.coefficients[range]
            .iter()
            .fold(0.0, |m: f64, x| m.max(x.abs()))
    }

    /// Configuration q, velocity q̇ and acceleration q̈ at time t (any real t; periodic).
    pub fn state_at(&self, t: f64, q: &mut [f64], v: &mut [f64], a: &mut [f64]) {
        let nb = basis_len(self.modes);
        let nc = self.layout.components();
        let (mut phi, mut d1, mut d2) = (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
        let theta = t / self.period;
        let (shifts, class) = self.layout.shift_classes();
        let mut last = usize::MAX;
        for r in 0..self.layout.dim() {
            if class[r] != last {
                last = class[r];
                basis_at(theta + shifts[last], self.modes, &mut phi, &mut d1, &mut d2);
            }
            let c = self.layout.component(r);
            let (mut x, mut dx, mut ddx) = (0.0, 0.0, 0.0);
            for m in 0..nb {
                let coef = self.coefficients[m * nc + c];
                x += phi[m] * coef;
                dx += d1[m] * coef;
                ddx += d2[m] * coef;
            }
            q[r] = x;
            v[r] = dx / self.period;
            a[r] = ddx / (self.period * self.period);
        }
    }

    /// The configuration at time t.
    pub fn position(&self, t: f64) -> Vec<f64> {
        let d = self.layout.dim();
        let (mut q, mut v, mut a) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
        self.state_at(t, &mut q, &mut v, &mut a);
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choreography_shifts_bodies_by_a_third_of_the_period() {
        let layout = Layout::Choreography {
            bodies: 3,
            body_dim: 2,
        };
        let mut c = FourierCurve::zeros(2, layout, 2.0).unwrap();
        c.set_mode(1, &[0.0, 0.0], &[1.0, 0.0]).unwrap();
        c.set_mode(2, &[0.0, 0.5], &[0.0, 0.0]).unwrap();
        let t = 0.3;
        let q = c.position(t);
        let later = c.position(t + 2.0 / 3.0);
        assert!((q[2] - later[0]).abs() < 1e-15 && (q[3] - later[1]).abs() < 1e-15);
        let x = (TAU * t / 2.0).sin();
        assert!((q[0] - x).abs() < 1e-15);
        assert!(c.set_mode(3, &[0.0, 0.0], &[0.0, 0.0]).is_err());
        assert!(FourierCurve::zeros(0, Layout::Orbit { dim: 1 }, 1.0).is_err());
        assert!(FourierCurve::zeros(1, Layout::Orbit { dim: 1 }, f64::NAN).is_err());
    }
}
