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
    #[error("invalid step size h = {h}: it must be finite and positive")]
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
    #[error("non-finite value in {what}: {value}")]
    NonFinite {
        /// What contained it.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A parameter of a system is out of its domain (e.g. a negative mass).
    #[error("invalid parameter {name} = {value}: {reason}")]
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
        "Newton solve failed at step {step} (t = {t}): residual {residual:.3e} after {iterations} \
         iterations ({reason})"
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

/// Shorthand for results with [`GviError`].
pub type Result<T, E = GviError> = std::result::Result<T, E>;

/// Check that every value is finite, naming the input in the error.
pub(crate) fn ensure_finite(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(GviError::NonFinite {
            what: what.to_string(),
            value,
        }),
        None => Ok(()),
    }
}

/// Check that a slice has the expected length.
pub(crate) fn ensure_len(what: &str, expected: usize, got: usize) -> Result<()> {
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
