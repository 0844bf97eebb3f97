//! The [`PlotError`] type and error-construction helpers.

/// Errors from chart rendering.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Nothing is left to draw (no series, or every point was filtered out).
    #[error("chart `{title}` has no plottable data")]
    NoData {
        /// Title of the offending chart.
        title: String,
    },
    /// The data cannot be drawn: its range overflows `f64`, or a heat-map
    /// coordinate is non-finite (or non-positive on a log axis).
    #[error("chart `{title}`: invalid data: {reason}")]
    InvalidData {
        /// Title of the offending chart.
        title: String,
        /// What is wrong with the data.
        reason: String,
    },
    /// Writing the SVG file (or creating its parent directory) failed.
    #[error("I/O error while saving chart: {0}")]
    Io(#[from] std::io::Error),
    /// The plotters backend reported an error.
    #[error("plotting backend error: {0}")]
    Backend(String),
}

impl PlotError {
    pub(super) fn no_data(title: &str) -> Self {
        let title = title.to_owned();
        Self::NoData { title }
    }
    pub(super) fn invalid(title: &str, reason: &str) -> Self {
        let (title, reason) = (title.to_owned(), reason.to_owned());
        Self::InvalidData { title, reason }
    }
}

pub(super) fn backend_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Backend(e.to_string())
}
