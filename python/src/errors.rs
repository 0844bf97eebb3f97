//! Typed Python exceptions: a base class `GalerkinError` and one subclass per kind of failure.
//! Bad input (`InvalidInputError` and its subclasses: shapes, non-finite values, the method,
//! parameters, expressions, scenes, work above the memory limit) is told apart from failures of a valid run (`SolverError`,
//! `NonFiniteResultError`, `UnsupportedError`).

use galerkin_vi::GviError;
use galerkin_vi_lab::error::LabError;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt};
use pyo3::prelude::*;
use pyo3::{PyErr, create_exception};

create_exception!(
    galerkin_vi,
    GalerkinError,
    PyException,
    "Base class of every galerkin_vi error."
);
create_exception!(
    galerkin_vi,
    InvalidInputError,
    GalerkinError,
    "An argument is malformed: a wrong value, an unknown basis, quadrature or solver name."
);
create_exception!(
    galerkin_vi,
    ShapeError,
    InvalidInputError,
    "An array has the wrong shape or length (the message names the argument)."
);
create_exception!(
    galerkin_vi,
    NonFiniteError,
    InvalidInputError,
    "An input contains NaN or infinity (the message names the argument)."
);
create_exception!(
    galerkin_vi,
    InvalidMethodError,
    InvalidInputError,
    "The method is invalid: n, h, steps, the quadrature or its strength for the basis."
);
create_exception!(
    galerkin_vi,
    InvalidParameterError,
    InvalidInputError,
    "A physical parameter is out of its domain (a negative mass, a zero length)."
);
create_exception!(
    galerkin_vi,
    ExpressionError,
    InvalidInputError,
    "An expression Lagrangian was rejected (syntax, unknown symbol, not regular)."
);
create_exception!(
    galerkin_vi,
    SceneError,
    InvalidInputError,
    "A scene is unknown or malformed."
);
create_exception!(
    galerkin_vi,
    MemoryLimitError,
    InvalidInputError,
    "The work would need more memory than the limit (4 GB, the gvi tool's): refused before \
     any work, the message quoting the estimate and the limit."
);
create_exception!(
    galerkin_vi,
    SolverError,
    GalerkinError,
    "The stage equations of a step could not be solved (Newton did not converge)."
);
create_exception!(
    galerkin_vi,
    NonFiniteResultError,
    GalerkinError,
    "The computed state became NaN or infinite."
);
create_exception!(
    galerkin_vi,
    UnsupportedError,
    GalerkinError,
    "The request is not supported for this system (e.g. rigid bodies from Python)."
);

/// Register the exception classes in the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GalerkinError", py.get_type::<GalerkinError>())?;
    m.add("InvalidInputError", py.get_type::<InvalidInputError>())?;
    m.add("ShapeError", py.get_type::<ShapeError>())?;
    m.add("NonFiniteError", py.get_type::<NonFiniteError>())?;
    m.add("InvalidMethodError", py.get_type::<InvalidMethodError>())?;
    m.add(
        "InvalidParameterError",
        py.get_type::<InvalidParameterError>(),
    )?;
    m.add("ExpressionError", py.get_type::<ExpressionError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("MemoryLimitError", py.get_type::<MemoryLimitError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add(
        "NonFiniteResultError",
        py.get_type::<NonFiniteResultError>(),
    )?;
    m.add("UnsupportedError", py.get_type::<UnsupportedError>())?;
    Ok(())
}

/// The exception of a library error.
pub fn core_error(e: GviError) -> PyErr {
    let msg = e.to_string();
    match e {
        GviError::InvalidBasisSize { .. }
        | GviError::InvalidStepSize { .. }
        | GviError::InvalidStepCount { .. }
        | GviError::InvalidQuadrature { .. }
        | GviError::QuadratureTooWeak { .. } => InvalidMethodError::new_err(msg),
        GviError::DimensionMismatch { .. } => ShapeError::new_err(msg),
        GviError::NonFinite { .. } => NonFiniteError::new_err(msg),
        GviError::InvalidParameter { .. } => InvalidParameterError::new_err(msg),
        GviError::InvalidInput { .. }
        | GviError::BasisNotAttached { .. }
        | GviError::Mismatch { .. } => InvalidInputError::new_err(msg),
        GviError::NewtonFailure { .. }
        | GviError::PeriodicNotConverged { .. }
        | GviError::PeriodicUnderResolved { .. } => SolverError::new_err(msg),
        GviError::NonFiniteResult { .. } => NonFiniteResultError::new_err(msg),
        GviError::Unsupported(_) => UnsupportedError::new_err(msg),
        GviError::Expression(_) => ExpressionError::new_err(msg),
        // Only a run stopped by a Python signal is interrupted, and then the signal's own
        // exception is raised instead (crate::interrupt).
        GviError::Interrupted { .. } => PyKeyboardInterrupt::new_err(msg),
    }
}

/// The exception of a lab error (scenes and their runs).
pub fn lab_error(e: LabError) -> PyErr {
    match e {
        LabError::Core(e) => core_error(e),
        LabError::Scene { .. } | LabError::Io { .. } => SceneError::new_err(e.to_string()),
        LabError::InvalidArgument { .. } => InvalidInputError::new_err(e.to_string()),
        LabError::Collision { .. } => NonFiniteResultError::new_err(e.to_string()),
        LabError::MemoryEstimate { .. } | LabError::MemoryTooHigh { .. } => {
            MemoryLimitError::new_err(e.to_string())
        }
        other => GalerkinError::new_err(other.to_string()),
    }
}

/// `map_err` shorthand for library results.
pub trait IntoPy<T> {
    /// Convert the error into its Python exception.
    fn py_err(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for Result<T, GviError> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(core_error)
    }
}

impl<T> IntoPy<T> for Result<T, LabError> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(lab_error)
    }
}
