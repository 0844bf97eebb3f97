//! The crate's typed error.
//!
//! Every failure that user input can cause is one of these variants: invalid method parameters,
//! mismatched dimensions, non-finite states, a quadrature too weak for the basis, a Newton solve
//! that does not converge, or a malformed scene. None of them panics.

use std::path::PathBuf;

/// Errors returned by the library and reported by the `gvi` command-line tool.
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
    /// A scene could not be found or parsed.
    #[error("scene error ({source_name}): {reason}")]
    Scene {
        /// The scene's name or path.
        source_name: String,
        /// What is wrong.
        reason: String,
    },
    /// A command-line argument is malformed.
    #[error("invalid argument {name}: {reason}")]
    InvalidArgument {
        /// Argument name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A requested feature is not available for this system (e.g. an exact solution).
    #[error("{0}")]
    Unsupported(String),
    /// Reading or writing a file failed.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An external work–precision file (`gvi work-precision --external`) could not be read.
    #[error("cannot read external work-precision file {path}: {source}")]
    ExternalFile {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An external work–precision file is malformed: a wrong or missing column, a malformed or
    /// non-finite number, a row with the wrong number of fields.
    #[error("{path}:{line}: {reason}")]
    ExternalCsv {
        /// The file.
        path: PathBuf,
        /// 1-based line number (1 is the header line).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A study would take an absurd time or memory; refused before any work is done.
    #[error(
        "refusing the sweep: {what} is estimated at {estimate:.3e}, above the limit \
         {limit:.0e} (shorten --horizon or the sweep)"
    )]
    CostTooHigh {
        /// What was estimated (total integration steps, samples).
        what: String,
        /// The estimate.
        estimate: f64,
        /// The documented limit.
        limit: f64,
    },
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
         {tolerance:.1e}); raise --modes"
    )]
    PeriodicUnderResolved {
        /// Number of modes K.
        modes: usize,
        /// Size of the last two modes relative to the largest mode.
        tail: f64,
        /// The accepted limit.
        tolerance: f64,
    },
    /// An output path is unusable (a directory, a pseudo-filesystem, the same file as another
    /// output or as an input); refused before any work is done.
    #[error("cannot write {path}: {reason}")]
    InvalidOutput {
        /// The output path.
        path: PathBuf,
        /// Why it is refused.
        reason: String,
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
    /// Two bodies coincide (or the force between them is not finite).
    #[error("bodies {a} and {b} collide at step {step} (t = {t:e}): separation {separation:e}")]
    Collision {
        /// First body.
        a: String,
        /// Second body.
        b: String,
        /// Step end at which they met.
        step: usize,
        /// Its time.
        t: f64,
        /// Their separation there.
        separation: f64,
    },
    /// With `--strict`: a run's error figures exceed the sanity threshold.
    #[error("the run is not trustworthy (--strict): {0}")]
    Untrustworthy(String),
    /// Every run of a study failed: there is no result to report.
    #[error("all {runs} runs of the study failed (first failure: {first})")]
    AllRunsFailed {
        /// Number of runs.
        runs: usize,
        /// The first failure's message.
        first: String,
    },
    /// A run would hold an absurd amount of memory; refused before any work is done.
    #[error(
        "refusing the run: {steps} steps at about {bytes_per_step:.0} bytes each need an \
         estimated {estimate:.3e} bytes, above the limit {limit:.0e} (a chart, JSON output and \
         --tol keep the whole trajectory; a plain CSV run is streamed and needs no such memory)"
    )]
    MemoryTooHigh {
        /// Steps requested.
        steps: usize,
        /// Estimated bytes per step.
        bytes_per_step: f64,
        /// Estimated total bytes.
        estimate: f64,
        /// The documented limit.
        limit: f64,
    },
    /// An expression Lagrangian (`type = "lagrangian"`) was rejected: a syntax error, an
    /// unknown symbol, a degenerate or non-regular Lagrangian (see
    /// [`ExpressionError`](crate::systems::expression::ExpressionError)).
    #[error("expression Lagrangian: {0}")]
    Expression(#[from] crate::systems::expression::ExpressionError),
    /// Serialisation failed.
    #[error("serialisation error: {0}")]
    Serialize(String),
    /// Chart rendering failed.
    #[error("chart error: {0}")]
    Plot(String),
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
