//! The crate's typed error.
//!
//! Every failure that user input can cause is one of these variants: invalid method parameters,
//! mismatched dimensions, non-finite states, a quadrature too weak for the basis, a Newton solve
//! that does not converge, or an invalid input. None of them panics. The `gvi` tool wraps them in its own error
//! type, which adds scene, file, chart and command-line failures.

mod expression;

pub use expression::{ExpressionError, Position};

/// Errors returned by the library.
#[derive(Debug, thiserror::Error)]
pub enum GviError {
    /// The number of basis functions is too small (every basis needs both end functions, and
    /// some bases need more) or too large for the basis.
    #[error("invalid number of basis functions n = {n} for the {basis} basis: {reason}")]
    InvalidBasisSize {
        /// Requested number of basis functions.
        n: usize,
        /// Name of the basis.
        basis: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The step size is not a positive finite number.
    #[error("invalid step size h = {}: it must be finite and positive", fmt_number(*.h))]
    InvalidStepSize {
        /// Requested step.
        h: f64,
    },
    /// The number of steps is invalid (zero or absurdly large).
    #[error("invalid number of steps {steps}: {reason}")]
    InvalidStepCount {
        /// Requested number of steps.
        steps: usize,
        /// Why it is rejected.
        reason: String,
    },
    /// The quadrature rule is invalid (no points, nodes outside [0, 1], non-finite weights).
    #[error("invalid quadrature: {reason}")]
    InvalidQuadrature {
        /// Why it is rejected.
        reason: String,
    },
    /// The quadrature does not integrate φ_a'φ_b' exactly, so the kinetic (stage) matrix of the
    /// discrete action is singular or numerically meaningless.
    #[error(
        "quadrature too weak for the basis: {quadrature} (degree of exactness {degree}) cannot \
         integrate products of derivatives of the {basis} basis with n = {n} (needs degree ≥ \
         {required}); kinetic-matrix reciprocal condition number {rcond:.3e}"
    )]
    QuadratureTooWeak {
        /// Quadrature name.
        quadrature: String,
        /// Its polynomial degree of exactness.
        degree: usize,
        /// Basis name.
        basis: String,
        /// Number of basis functions.
        n: usize,
        /// Degree needed to integrate φ_a'φ_b' exactly (for polynomial bases).
        required: usize,
        /// Estimated reciprocal condition number of the interior kinetic matrix.
        rcond: f64,
    },
    /// Two dimensions that must agree do not.
    #[error("dimension mismatch for {what}: expected {expected}, got {got}")]
    DimensionMismatch {
        /// What was being checked.
        what: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A value given by the user is NaN or infinite.
    #[error("non-finite value in {what}: {}", fmt_number(*.value))]
    NonFinite {
        /// What contained it.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A parameter of a system is out of its domain (e.g. a negative mass).
    #[error("invalid parameter {name} = {}: {reason}", fmt_number(*.value))]
    InvalidParameter {
        /// Parameter name.
        name: String,
        /// Its value.
        value: f64,
        /// Why it is rejected.
        reason: String,
    },
    /// The Newton solve of one step's stage equations did not converge. The trajectory computed
    /// up to the failing step is kept in [`crate::IntegrationFailure`].
    #[error(
        "Newton solve failed at step {step} (t = {}): residual {residual:.3e} after \
         {iterations} iterations ({reason})",
        fmt_number(*.t)
    )]
    NewtonFailure {
        /// Index of the step that failed (0-based: step k maps t_k to t_{k+1}).
        step: usize,
        /// Time at the start of the failing step.
        t: f64,
        /// Max-norm of the stage-equation residual at the last iterate.
        residual: f64,
        /// Newton iterations taken.
        iterations: usize,
        /// Why it stopped (diverged, non-finite, singular Jacobian, iteration limit).
        reason: String,
    },
    /// A deserialised trajectory's curves are in a basis written outside the crate, which
    /// serialisation cannot carry: attach it with
    /// [`Trajectory::attach_basis`](crate::Trajectory::attach_basis) before dense output.
    #[error(
        "the trajectory's curves are in the user basis '{basis}', which is not attached: \
         call Trajectory::attach_basis with it before reading the curves"
    )]
    BasisNotAttached {
        /// Name of the basis recorded in the trajectory.
        basis: String,
    },
    /// Two things that must belong together do not: a basis attached to a trajectory made with
    /// another, or a workspace used with an integrator or system it was not made for.
    #[error("mismatch: expected {expected}, got {got}")]
    Mismatch {
        /// What was expected.
        expected: String,
        /// What was given.
        got: String,
    },
    /// An input to a library function is invalid (named, with the reason).
    #[error("invalid {name}: {reason}")]
    InvalidInput {
        /// The input's name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A requested feature is not available for this system (e.g. an exact solution).
    #[error("{0}")]
    Unsupported(String),
    /// The Newton iteration for a periodic orbit (stationary point of the action over one
    /// period, [`crate::periodic`]) did not converge.
    #[error(
        "periodic orbit not found: Newton residual {residual:.3e} after {iterations} \
         iterations ({reason})"
    )]
    PeriodicNotConverged {
        /// Max-norm of the gradient of the action (and of the energy condition) at the last
        /// iterate.
        residual: f64,
        /// Newton iterations taken.
        iterations: usize,
        /// Why it stopped (diverged, non-finite, iteration limit).
        reason: String,
    },
    /// A periodic orbit was found but its Fourier series is not resolved by K modes.
    #[error(
        "too few modes: with K = {modes} the last modes are {tail:.3e} of the largest (limit \
         {tolerance:.1e}); raise the number of modes K"
    )]
    PeriodicUnderResolved {
        /// Number of modes K.
        modes: usize,
        /// Size of the last two modes relative to the largest mode.
        tail: f64,
        /// The accepted limit.
        tolerance: f64,
    },
    /// The computed state or an invariant became NaN or infinite. The steps before `step` are
    /// kept (written, for `gvi run`).
    #[error(
        "non-finite {what} = {value:e} at step {step} (t = {t:e}); the {step} steps before it \
         are kept"
    )]
    NonFiniteResult {
        /// What became non-finite (a position, a momentum, an invariant).
        what: String,
        /// The value.
        value: f64,
        /// Index of the first step end where it happened.
        step: usize,
        /// Its time.
        t: f64,
    },
    /// The caller asked the run to stop (its `stop` callback returned true, e.g. on Ctrl-C)
    /// before step `step`; the steps before it are kept
    /// ([`solve_until`](crate::solve::solve_until)).
    #[error("stopped on request before step {step} (t = {}); the {step} steps before it are kept", fmt_number(*.t))]
    Interrupted {
        /// Index of the first step not computed.
        step: usize,
        /// Its start time.
        t: f64,
    },
    /// An expression Lagrangian (`type = "lagrangian"`) was rejected: a syntax error, an
    /// unknown symbol, a degenerate or non-regular Lagrangian (see
    /// [`ExpressionError`]).
    #[error("{}", expression_message(.0))]
    Expression(#[from] ExpressionError),
}

/// `expression Lagrangian: …`, or for an error in another expression of the system (`exact`,
/// `force`) the message naming that expression.
fn expression_message(e: &ExpressionError) -> String {
    match e {
        ExpressionError::In { .. } => e.to_string(),
        e => format!("expression Lagrangian: {e}"),
    }
}

/// A number for messages: plain when it reads well (1e-4 ≤ |x| < 1e6, or 0), scientific
/// otherwise (`{}` would print 1e300 as a 301-digit integer).
pub fn fmt_number(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Shorthand for results with [`GviError`].
pub type Result<T, E = GviError> = std::result::Result<T, E>;

/// Check that every value is finite, naming the input in the error.
pub fn ensure_finite(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(GviError::NonFinite {
            what: what.to_string(),
            value,
        }),
        None => Ok(()),
    }
}

/// Check the state a one-step method is handed: q, p and the outputs q_next, p_next of length
/// `dim` each, q and p finite.
pub fn ensure_step_state(
    dim: usize,
    q: &[f64],
    p: &[f64],
    q_next: &[f64],
    p_next: &[f64],
) -> Result<()> {
    for (name, len) in [
        ("q", q.len()),
        ("p", p.len()),
        ("q_next", q_next.len()),
        ("p_next", p_next.len()),
    ] {
        ensure_len(name, dim, len)?;
    }
    ensure_finite("q", q)?;
    ensure_finite("p", p)
}

/// Check that a slice has the expected length.
pub fn ensure_len(what: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(GviError::DimensionMismatch {
            what: what.to_string(),
            expected,
            got,
        })
    }
}
