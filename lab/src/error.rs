//! Errors of the lab.
pub use galerkin_vi::error::*;
