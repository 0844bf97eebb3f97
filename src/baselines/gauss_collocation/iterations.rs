//! The iterations of the Gauss collocation baseline's stage equations, each a
//! [`NewtonIteration`] run by the crate's one driver: simplified Newton ([`StageNewton`]) and
//! the fixed-point iteration ([`FixedPoint`], over the dynamic [`Stages`] or the fixed-size
//! [`StaticStages`] map), with their termination values.

use super::{GaussCollocationBaseline, MAX_GAUSS_STAGES};
use crate::lagrangian::Lagrangian;
use crate::newton::{
    Adapt, ConvergedBy, Correction, Divergence, NewtonFailure, NewtonIteration, Progress,
    Termination,
};

/// Iteration cap of the simplified Newton solve.
pub(super) const MAX_ITERATIONS: usize = 60;

/// Iteration cap of the fixed-point iteration (then simplified Newton takes over).
const FIXED_POINT_ITERATIONS: usize = 30;

/// The fixed-point iteration converged when max |ΔZ| ≤ this · max(|q|); …
const FIXED_POINT_TOLERANCE: f64 = 1e-15;

/// … or, once it stopped contracting (θ above [`FIXED_POINT_STALL`]), at the round-off floor,
/// max |ΔZ| ≤ this · max(|q|).
const FIXED_POINT_FLOOR: f64 = 1e-14;

/// Contraction per iteration above which the fixed-point iteration has stopped contracting
/// (from its third iteration on): it hands over to simplified Newton unless at the floor.
const FIXED_POINT_STALL: f64 = 0.5;

/// The largest double below a positive `x`: `|δ| ≤ below(x)` is `|δ| < x` (the driver's floor
/// test is `≤`, this solver's `<`).
fn below(x: f64) -> f64 {
    debug_assert!(x > 0.0);
    f64::from_bits(x.to_bits() - 1)
}

/// The contraction above which the simplified Newton increment has stopped decreasing: the
/// largest double below 1, so that `θ >` it means `|δ| ≥ |δ_prev|` (a quotient of doubles below
/// 1 is at most the double below 1).
const NEWTON_FLOOR_THETA: f64 = f64::from_bits(1f64.to_bits() - 1);

/// The simplified Newton iteration on the stage equations Z = h² (A² ⊗ M⁻¹) F(Z) as a
/// [`NewtonIteration`] run by the crate's Newton driver ([`crate::newton::drive`]): the
/// residual R = h² (A² ⊗ I) M⁻¹F − Z and the LU of I − h² (A² ⊗ M⁻¹ ∂f(q)), factorised once
/// per step (Hairer, Lubich & Wanner, *Geometric Numerical Integration*, §VIII.6).
pub(super) struct StageNewton<'g, 'a, L: Lagrangian> {
    pub(super) g: &'g mut GaussCollocationBaseline<'a, L>,
    pub(super) q: &'g [f64],
    /// The iteration matrix is singular (reported at the first correction, after a residual).
    pub(super) singular: bool,
    /// max(|q|) (at least 1e-300).
    pub(super) scale: f64,
    /// The last residual's max-norm.
    pub(super) residual: f64,
}

impl<L: Lagrangian> StageNewton<'_, '_, L> {
    /// Converged at round-off: the increment is at machine level of q (`tiny`, the driver's
    /// tolerance test), or it has stopped decreasing (θ ≥ 1) while already small compared
    /// with q and Z (the floor test, 1e-10 · `zmax`). The two tests have different scales, so
    /// the corrections are reported with scale 1 and the scales are folded into the tolerance
    /// and the floor (the largest doubles below the thresholds where this solver's tests are
    /// strict), which keeps the maps bit for bit those of the hand-written loop this replaces.
    /// Diverging: an increment more than twice the previous one after 8 iterations.
    pub(super) fn termination(&self, zmax: f64) -> Termination {
        Termination {
            divergence: Some(Divergence {
                after: 8,
                growth: 2.0,
            }),
            ..Termination::new(
                MAX_ITERATIONS,
                1e-15 * self.scale,
                None,
                below(1e-10 * zmax),
                NEWTON_FLOOR_THETA,
            )
        }
    }

    fn failure(&self, iteration: usize, reason: &str) -> NewtonFailure {
        NewtonFailure {
            residual: self.residual,
            iterations: iteration + 1,
            reason: reason.into(),
        }
    }
}

impl<L: Lagrangian> NewtonIteration for StageNewton<'_, '_, L> {
    fn residual(&mut self, _: usize) -> f64 {
        let g = &mut *self.g;
        let (d, s, h) = (g.parts.d, g.s, g.h);
        g.eval_forces(self.q);
        g.iterations += 1;
        // Residual R = h² (A² ⊗ I) M⁻¹F − Z.
        for i in 0..s {
            for r in 0..d {
                let sum: f64 = (0..s).map(|j| g.a2[i * s + j] * g.minv_f[j * d + r]).sum();
                g.res[i * d + r] = h * h * sum - g.z[i * d + r];
            }
        }
        self.residual = amax(&g.res);
        self.residual
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        if self.singular {
            return Err(self.failure(iteration, "singular iteration matrix"));
        }
        let g = &mut *self.g;
        // The increment, in place of the residual.
        g.lu.solve_in_place(&mut g.res, &mut g.scratch);
        let size = amax(&g.res);
        if !size.is_finite() {
            return Err(self.failure(iteration, "non-finite iterate"));
        }
        for (z, dz) in g.z.iter_mut().zip(&g.res) {
            *z += dz;
        }
        let zmax = g.z.iter().fold(self.scale, |m, x| m.max(x.abs()));
        let correction = Correction { size, scale: 1.0 };
        Ok((correction, self.termination(zmax)))
    }

    /// At machine level (the tolerance test) the forces of the last iterate are the
    /// converged ones; at the floor they are re-evaluated: Z can be h² times larger than the
    /// forces it carries.
    fn finish(&mut self, by: ConvergedBy) -> Result<(), NewtonFailure> {
        if by == ConvergedBy::Floor {
            self.g.eval_forces(self.q);
        }
        Ok(())
    }
}

/// max |x| (NaN entries ignored, as `f64::max` does: a NaN increment shows in the next
/// residual and in the final state check).
fn amax(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The stage values a fixed-point iteration runs on: the general step's buffers or the
/// static kernel's fixed-size arrays.
pub(super) trait StageMap {
    /// One application of the map Z ← h² (A² ⊗ M⁻¹) F(Z); returns max |ΔZ|.
    fn update(&mut self) -> f64;
    /// The forces at the converged Z.
    fn refresh(&mut self);
}

/// The general step's stages ([`GaussCollocationBaseline::fixed_point_update`]).
pub(super) struct Stages<'g, 'a, L: Lagrangian> {
    pub(super) g: &'g mut GaussCollocationBaseline<'a, L>,
    pub(super) q: &'g [f64],
}

impl<L: Lagrangian> StageMap for Stages<'_, '_, L> {
    fn update(&mut self) -> f64 {
        self.g.fixed_point_update(self.q)
    }
    fn refresh(&mut self) {
        self.g.eval_forces(self.q);
    }
}

/// The static kernel's stages (`StaticKernel::advance`), fixed-size.
pub(super) struct StaticStages<'g, 'a, L: Lagrangian, const D: usize> {
    pub(super) g: &'g mut GaussCollocationBaseline<'a, L>,
    pub(super) q: &'g [f64; D],
    pub(super) v0: &'g [f64; D],
    pub(super) z: &'g mut [[f64; D]; MAX_GAUSS_STAGES],
    pub(super) f: &'g mut [[f64; D]; MAX_GAUSS_STAGES],
    pub(super) minv_f: &'g mut [[f64; D]; MAX_GAUSS_STAGES],
}

impl<L: Lagrangian, const D: usize> StageMap for StaticStages<'_, '_, L, D> {
    #[inline(always)]
    fn update(&mut self) -> f64 {
        let g = &mut *self.g;
        g.eval_forces_static(self.q, self.v0, self.z, self.f, self.minv_f);
        g.iterations += 1;
        let (s, h) = (g.s, g.h);
        let mut change = 0.0f64;
        for i in 0..s {
            for r in 0..D {
                let sum: f64 = (0..s).map(|j| g.a2[i * s + j] * self.minv_f[j][r]).sum();
                let zn = h * h * sum;
                change = change.max((zn - self.z[i][r]).abs());
                self.z[i][r] = zn;
            }
        }
        change
    }
    fn refresh(&mut self) {
        self.g
            .eval_forces_static(self.q, self.v0, self.z, self.f, self.minv_f);
    }
}

/// The termination of the fixed-point iteration after `corrections` iterations: converged
/// when max |ΔZ| ≤ 1e-15 · max(|q|), or — from the third iteration on, once it stopped
/// contracting (θ > ½) — at the round-off floor 1e-14 · max(|q|). (The first two increments
/// are not compared: the first is Z itself.)
pub(super) fn fixed_point_termination(corrections: usize) -> Termination {
    let floor = if corrections > 2 {
        FIXED_POINT_FLOOR
    } else {
        0.0
    };
    Termination::new(
        FIXED_POINT_ITERATIONS,
        FIXED_POINT_TOLERANCE,
        None,
        floor,
        FIXED_POINT_STALL,
    )
}

/// The fixed-point iteration Z ← h² (A² ⊗ M⁻¹) F(Z) from Z = 0 as a [`NewtonIteration`] (the
/// simplified Newton iteration with the identity for its matrix): cheap for small steps of
/// non-stiff problems. It gives up — leaving simplified Newton to do the work — when it stops
/// contracting above the floor, when an increment is not finite, or at its iteration limit.
pub(super) struct FixedPoint<M: StageMap> {
    map: M,
    /// max(|q|) (at least 1e-300): the scale of the tolerance and the floor.
    scale: f64,
    /// The last increment.
    last: f64,
}

impl<M: StageMap> FixedPoint<M> {
    pub(super) fn new(map: M, scale: f64) -> Self {
        FixedPoint {
            map,
            scale,
            last: 0.0,
        }
    }
}

impl<M: StageMap> NewtonIteration for FixedPoint<M> {
    /// The map is applied once per iteration, in `correct` (the increment G(Z) − Z is the
    /// residual of the iterate before it); this reports the last increment (0 before the
    /// first), so that stopping at the iteration limit costs no further force evaluation.
    fn residual(&mut self, _: usize) -> f64 {
        self.last
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        self.last = self.map.update();
        let correction = Correction {
            size: self.last,
            scale: self.scale,
        };
        Ok((correction, fixed_point_termination(iteration + 1)))
    }

    fn adapt(&mut self, progress: &Progress) -> Adapt {
        let stalled = progress.growing || progress.theta > FIXED_POINT_STALL;
        if progress.iteration > 2 && stalled {
            Adapt::GiveUp
        } else {
            Adapt::Continue
        }
    }

    fn finish(&mut self, _: ConvergedBy) -> Result<(), NewtonFailure> {
        self.map.refresh();
        Ok(())
    }
}
