//! The lab's typed error: every library error ([`GviError`]) plus the failures of scenes,
//! files, charts, studies and command-line arguments. Nothing here panics on user input.
//!
//! Library errors pass through unchanged as [`LabError::Core`] (their messages are the
//! library's), so a caller can match on the [`GviError`] inside with [`LabError::core`].

pub use galerkin_vi::error::{GviError, ensure_finite, ensure_len, fmt_number};
use std::path::PathBuf;

/// Errors of the `gvi` tool and its lab.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// A library error (method parameters, dimensions, non-finite states, Newton failures).
    #[error(transparent)]
    Core(#[from] GviError),
    /// A scene could not be found or parsed.
    #[error("scene error ({source_name}): {reason}")]
    Scene {
        /// The scene's name or path.
        source_name: String,
        /// What is wrong.
        reason: String,
    },
    /// A command-line argument or study setting is malformed.
    #[error("invalid argument {name}: {reason}")]
    InvalidArgument {
        /// Argument name.
        name: String,
        /// What is wrong.
        reason: String,
    },
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
    /// An output path is unusable (a directory, a pseudo-filesystem, the same file as another
    /// output or as an input); refused before any work is done.
    #[error("cannot write {path}: {reason}")]
    InvalidOutput {
        /// The output path.
        path: PathBuf,
        /// Why it is refused.
        reason: String,
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
    /// Work whose estimated memory is above the limit ([`crate::memory::ensure_fits`]);
    /// refused before any work is done.
    #[error(
        "refusing {what}: it needs an estimated {estimate:.3e} bytes of memory, above the \
         limit {limit:.0e} ({hint})"
    )]
    MemoryEstimate {
        /// The work refused.
        what: String,
        /// Estimated bytes.
        estimate: f64,
        /// The limit ([`crate::memory::LIMIT_BYTES`]).
        limit: f64,
        /// What to shrink.
        hint: String,
    },
    /// A streamed run stopped by Ctrl-C (SIGINT) before step `step`: the rows before it are
    /// kept (`kept` says where).
    #[error("interrupted (Ctrl-C) before step {step}: {kept}")]
    Interrupted {
        /// The first step not computed.
        step: usize,
        /// Where the rows computed before it are.
        kept: String,
    },
    /// Serialisation failed.
    #[error("serialisation error: {0}")]
    Serialize(String),
    /// Chart rendering failed.
    #[error("chart error: {0}")]
    Plot(String),
}

impl From<galerkin_vi::systems::expression::ExpressionError> for LabError {
    fn from(e: galerkin_vi::systems::expression::ExpressionError) -> Self {
        LabError::Core(e.into())
    }
}

impl From<galerkin_vi::IntegrationFailure> for LabError {
    fn from(f: galerkin_vi::IntegrationFailure) -> Self {
        LabError::Core(f.into())
    }
}

impl LabError {
    /// Whether this is a write to a pipe whose reader has gone (`gvi scenes | head -1`): not a
    /// failure to report, the tool just stops (`main` exits quietly with status 141, as a
    /// tool killed by SIGPIPE does).
    pub fn is_broken_pipe(&self) -> bool {
        matches!(self, LabError::Io { source, .. } if source.kind() == std::io::ErrorKind::BrokenPipe)
    }

    /// The library error inside, if this is one.
    pub fn core(&self) -> Option<&GviError> {
        match self {
            LabError::Core(e) => Some(e),
            _ => None,
        }
    }
}

/// Shorthand for results with [`LabError`].
pub type Result<T, E = LabError> = std::result::Result<T, E>;
