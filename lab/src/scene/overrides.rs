//! [`Overrides`]: changes to a scene's method and initial state, parsed (by the command line or
//! a program) before the scene is built, so that [`Scene::build`] checks the state that runs.

use super::Scene;
use galerkin_vi::adaptive::ErrorControl;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::integrator::StageSolver;
use galerkin_vi::lie::Retraction;
use galerkin_vi::quadrature::QuadratureKind;

/// Replacements for a scene's `[method]` and `[initial]` values; `None` (or `false`) keeps the
/// scene's own.
///
/// ```
/// use galerkin_vi_lab::scene::{Overrides, Scene};
/// let scene = Scene::load("kepler")?.with_overrides(&Overrides {
///     n: Some(12),
///     steps: Some(5),
///     ..Overrides::default()
/// });
/// let built = scene.build()?;
/// assert_eq!((built.method.n, built.method.steps), (12, 5));
/// # Ok::<(), galerkin_vi_lab::error::LabError>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// Basis kind.
    pub basis: Option<BasisKind>,
    /// Quadrature kind.
    pub quadrature: Option<QuadratureKind>,
    /// Number of basis functions n.
    pub n: Option<usize>,
    /// Number of quadrature points.
    pub quad_points: Option<usize>,
    /// Use the quadrature's economical number of points for n, unless `quad_points` is given.
    pub economical: bool,
    /// Step size h.
    pub h: Option<f64>,
    /// Stage solver.
    pub solver: Option<StageSolver>,
    /// Number of steps.
    pub steps: Option<usize>,
    /// Retraction of the rigid-body integrator.
    pub retraction: Option<Retraction>,
    /// Initial position.
    pub q0: Option<Vec<f64>>,
    /// Initial momentum.
    pub p0: Option<Vec<f64>>,
    /// Tolerance of a tolerance-driven run.
    pub tol: Option<f64>,
    /// Error control of a tolerance-driven run.
    pub control: Option<ErrorControl>,
    /// The values of n a tolerance-driven run may use.
    pub ladder: Option<Vec<usize>>,
    /// Choose h from the tolerance.
    pub auto_h: bool,
    /// Enrichment frequencies of the enriched basis (one ω or several).
    pub omega: Option<Vec<f64>>,
    /// Number of harmonics of the enriched basis.
    pub harmonics: Option<usize>,
    /// A Poincaré time transformation with this monitor (replacing the scene's monitor, or
    /// adding `[method.time_transform]` with its defaults).
    pub time_transform: Option<galerkin_vi::time_transform::MonitorKind>,
    /// The monitor's exponent α (needs a time transformation).
    pub time_alpha: Option<f64>,
    /// The energy level E₀ of the time transformation.
    pub time_energy: Option<f64>,
    /// The physical end time of a time-transformed run.
    pub t_end: Option<f64>,
    /// Rows at t₀ + k·every in physical time (time-transformed runs).
    pub every: Option<f64>,
}

impl Scene {
    /// The scene with `overrides` applied (build it afterwards: [`Scene::build`] checks the
    /// resulting initial state and method).
    pub fn with_overrides(mut self, o: &Overrides) -> Scene {
        let m = &mut self.method;
        if let Some(b) = o.basis {
            // Another basis drops the scene's enrichment parameters (only the enriched basis
            // takes them); given on the command line too, they are refused when it is built.
            if !b.is_parametrised() {
                m.omega = None;
                m.harmonics = None;
            }
            m.basis = b;
        }
        if o.omega.is_some() {
            m.omega = o.omega.clone();
        }
        if o.harmonics.is_some() {
            m.harmonics = o.harmonics;
        }
        if let Some(q) = o.quadrature {
            m.quadrature = q;
        }
        if let Some(n) = o.n {
            m.n = n;
        }
        if let Some(s) = o.solver {
            m.solver = s;
        }
        if o.quad_points.is_some() {
            m.quad_points = o.quad_points;
        }
        if o.economical && o.quad_points.is_none() {
            m.quad_points = Some(m.quadrature.economical_points(m.n));
        }
        if let Some(h) = o.h {
            m.h = h;
        }
        if let Some(s) = o.steps {
            m.steps = s;
        }
        if let Some(r) = o.retraction {
            m.retraction = Some(r);
        }
        if o.tol.is_some() {
            m.tol = o.tol;
        }
        if let Some(c) = o.control {
            m.control = Some(c);
        }
        if o.auto_h {
            m.auto_h = true;
        }
        if let Some(l) = &o.ladder {
            m.ladder = Some(l.clone());
        }
        if let Some(kind) = o.time_transform {
            let spec = m
                .time_transform
                .get_or_insert_with(|| galerkin_vi::time_transform::TimeTransformSpec::new(kind));
            spec.monitor = kind;
        }
        if let Some(spec) = &mut m.time_transform {
            if let Some(a) = o.time_alpha {
                spec.alpha = a;
            }
            if o.time_energy.is_some() {
                spec.energy = o.time_energy;
            }
            if o.t_end.is_some() {
                spec.t_end = o.t_end;
            }
            if o.every.is_some() {
                spec.every = o.every;
            }
        }
        if let Some(q) = &o.q0 {
            self.initial.q = q.clone();
        }
        if let Some(p) = &o.p0 {
            self.initial.p = p.clone();
        }
        self
    }
}
