//! Energy and momentum maps along a trajectory: at the step ends and along the Galerkin
//! curves (dense output).

use super::MomentumMap;
use crate::error::{GviError, Result, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::systems::System;
use crate::trajectory::Trajectory;

/// A scalar quantity sampled at a sequence of times.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Sample times.
    pub t: Vec<f64>,
    /// Values at those times.
    pub values: Vec<f64>,
}

impl Series {
    /// |value − first value| at every sample (the error of a conserved quantity).
    pub fn deviations(&self) -> Vec<f64> {
        let v0 = self.values.first().copied().unwrap_or(0.0);
        self.values.iter().map(|v| (v - v0).abs()).collect()
    }

    /// Largest |value − first value| (0 for an empty series); NaN if any value is NaN, so
    /// that a run that blew up is never reported as conserving the quantity (`f64::max`
    /// would drop the NaN: [`crate::reduce`]).
    pub fn max_deviation(&self) -> f64 {
        crate::reduce::max_error(self.deviations())
    }

    /// Mean |value − first value| (0 for an empty series).
    pub fn mean_deviation(&self) -> f64 {
        let d = self.deviations();
        if d.is_empty() {
            0.0
        } else {
            d.iter().sum::<f64>() / d.len() as f64
        }
    }

    /// Least-squares straight line through (t, value); see [`linear_trend`].
    pub fn trend(&self) -> Trend {
        linear_trend(&self.t, &self.values)
    }
}

/// A least-squares straight line y ≈ intercept + slope · t, with the root-mean-square of the
/// residuals about it (the spread that a drift slope·T must be compared with).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Trend {
    /// Slope.
    pub slope: f64,
    /// Intercept.
    pub intercept: f64,
    /// RMS of the residuals y − (intercept + slope t).
    pub spread: f64,
    /// Time span T = t_last − t_first.
    pub span: f64,
}

impl Trend {
    /// The drift over the whole span, |slope| · T.
    pub fn drift(&self) -> f64 {
        self.slope.abs() * self.span
    }
}

/// Least-squares line through the points (t_i, y_i); zeros for fewer than two points or a
/// zero time span. Uses centred sums (stable for long runs).
pub fn linear_trend(t: &[f64], y: &[f64]) -> Trend {
    let n = t.len().min(y.len());
    if n < 2 {
        return Trend::default();
    }
    let (t, y) = (&t[..n], &y[..n]);
    let tm = t.iter().sum::<f64>() / n as f64;
    let ym = y.iter().sum::<f64>() / n as f64;
    let (mut stt, mut sty) = (0.0, 0.0);
    for i in 0..n {
        stt += (t[i] - tm) * (t[i] - tm);
        sty += (t[i] - tm) * (y[i] - ym);
    }
    let span = t[n - 1] - t[0];
    if stt <= 0.0 {
        return Trend {
            slope: 0.0,
            intercept: ym,
            spread: 0.0,
            span,
        };
    }
    let slope = sty / stt;
    let intercept = ym - slope * tm;
    let ss = (0..n)
        .map(|i| (y[i] - intercept - slope * t[i]).powi(2))
        .sum::<f64>();
    Trend {
        slope,
        intercept,
        spread: (ss / n as f64).sqrt(),
        span,
    }
}

/// The system's invariant called `energy` at every step end (q_k, p_k).
pub fn energy_at_step_ends<S: System>(system: &S, traj: &Trajectory) -> Result<Series> {
    ensure_len("trajectory dimension", system.dim(), traj.dim)?;
    let names = system.invariant_names();
    let idx = names.iter().position(|n| *n == "energy").ok_or_else(|| {
        GviError::Unsupported(format!("system {} has no energy invariant", system.name()))
    })?;
    let mut inv = vec![0.0; names.len()];
    let mut values = Vec::with_capacity(traj.q.len());
    for (q, p) in traj.q.iter().zip(&traj.p) {
        system.invariants(q, p, &mut inv);
        values.push(inv[idx]);
    }
    Ok(Series {
        t: traj.times(),
        values,
    })
}

/// The energy E = L_v·q̇ − L along the Galerkin curves, at `samples_per_step` equally spaced
/// points inside every step plus the final time ([`Trajectory::sample_times`]).
pub fn energy_along_curves<L: Lagrangian>(
    lagrangian: &L,
    traj: &Trajectory,
    samples_per_step: usize,
) -> Result<Series> {
    ensure_len("trajectory dimension", lagrangian.dim(), traj.dim)?;
    let t = traj.sample_times(samples_per_step);
    let mut values = Vec::with_capacity(t.len());
    for &s in &t {
        let (q, v) = traj.state_on_curve(s)?;
        values.push(lagrangian.energy_at(s, &q, &v));
    }
    Ok(Series { t, values })
}

/// The momentum map J(q_k, p_k) at every step end.
pub fn momentum_at_step_ends<M: MomentumMap + ?Sized>(map: &M, traj: &Trajectory) -> Series {
    Series {
        t: traj.times(),
        values: traj
            .q
            .iter()
            .zip(&traj.p)
            .map(|(q, p)| map.value(q, p))
            .collect(),
    }
}

/// The momentum map along the Galerkin curves, J(q(t), p(t)) with p(t) = ∂L/∂v(q(t), q̇(t)),
/// at `samples_per_step` points per step plus the final time.
pub fn momentum_along_curves<L: Lagrangian, M: MomentumMap + ?Sized>(
    lagrangian: &L,
    map: &M,
    traj: &Trajectory,
    samples_per_step: usize,
) -> Result<Series> {
    ensure_len("trajectory dimension", lagrangian.dim(), traj.dim)?;
    let t = traj.sample_times(samples_per_step);
    let mut values = Vec::with_capacity(t.len());
    let mut p = vec![0.0; traj.dim];
    for &s in &t {
        let (q, v) = traj.state_on_curve(s)?;
        lagrangian.legendre_transform_at(s, &q, &v, &mut p);
        values.push(map.value(&q, &p));
    }
    Ok(Series { t, values })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trend_of_a_line_and_noise() {
        let t: Vec<f64> = (0..100).map(f64::from).collect();
        let y: Vec<f64> = t.iter().map(|x| 2.0 + 0.5 * x).collect();
        let tr = linear_trend(&t, &y);
        assert!((tr.slope - 0.5).abs() < 1e-12 && (tr.intercept - 2.0).abs() < 1e-10);
        assert!(tr.spread < 1e-10 && (tr.drift() - 49.5).abs() < 1e-9);
        let alt: Vec<f64> = (0..100)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let tr = linear_trend(&t, &alt);
        assert!(tr.drift() < 0.1 * tr.spread);
        assert_eq!(linear_trend(&[1.0], &[2.0]), Trend::default());
    }

    /// A blown-up run (a NaN energy at one step) is never reported as conserving the energy:
    /// the max deviation is NaN. Negative control: the fold with `f64::max` it replaces gives
    /// the finite 0.5 for the same series.
    #[test]
    fn max_deviation_of_a_series_with_a_nan_is_nan() {
        let series = Series {
            t: vec![0.0, 1.0, 2.0, 3.0],
            values: vec![1.0, 1.5, f64::NAN, 1.25],
        };
        assert!(series.max_deviation().is_nan());
        let old = series.deviations().into_iter().fold(0.0, f64::max);
        assert_eq!(old, 0.5);
        let clean = Series {
            t: vec![0.0, 1.0],
            values: vec![1.0, 1.5],
        };
        assert_eq!(clean.max_deviation(), 0.5);
        assert_eq!(Series::default().max_deviation(), 0.0);
    }
}
