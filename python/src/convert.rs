//! Checked conversion of Python inputs to vectors and of results to numpy arrays. Every
//! check names the argument: a wrong shape is a `ShapeError`, NaN or infinity a
//! `NonFiniteError`, something that is not numbers an `InvalidInputError`.

use crate::errors::{InvalidInputError, NonFiniteError, ShapeError};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// `obj` as a float64 numpy array (lists, tuples, scalars and integer arrays are converted).
fn as_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let py = obj.py();
    let converted = py
        .import("numpy")?
        .call_method1("asarray", (obj, "float64"))
        .map_err(|e| {
            InvalidInputError::new_err(format!("{name}: not an array of numbers ({e})"))
        })?;
    converted
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|_| InvalidInputError::new_err(format!("{name}: not an array of numbers")))
}

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn check_finite(name: &str, values: &[f64], columns: usize) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => {
            let at = match i.checked_div(columns) {
                None => format!("[{i}]"),
                Some(row) => format!("[{row}, {}]", i % columns),
            };
            Err(NonFiniteError::new_err(format!(
                "{name}{at} = {} is not finite",
                values[i]
            )))
        }
    }
}

/// A 1-D array of `len` finite numbers (any length when `len` is `None`).
pub fn vector(obj: &Bound<'_, PyAny>, name: &str, len: Option<usize>) -> PyResult<Vec<f64>> {
    let a = as_array(obj, name)?;
    let shape = a.shape().to_vec();
    let ok = shape.len() == 1 && len.is_none_or(|n| shape[0] == n);
    if !ok {
        let want = match len {
            Some(n) => format!("a 1-D array of length {n}"),
            None => "a 1-D array".to_string(),
        };
        return Err(ShapeError::new_err(format!(
            "{name}: expected {want}, got shape {}",
            shape_text(&shape)
        )));
    }
    let v: Vec<f64> = a.readonly().as_array().iter().copied().collect();
    check_finite(name, &v, 0)?;
    Ok(v)
}

/// A 2-D array (rows × `cols`) of finite numbers, as rows.
pub fn matrix(obj: &Bound<'_, PyAny>, name: &str, cols: usize) -> PyResult<Vec<Vec<f64>>> {
    let a = as_array(obj, name)?;
    let shape = a.shape().to_vec();
    if shape.len() != 2 || shape[1] != cols || shape[0] == 0 {
        return Err(ShapeError::new_err(format!(
            "{name}: expected a 2-D array of shape (members, {cols}) with at least one row, \
             got shape {}",
            shape_text(&shape)
        )));
    }
    let flat: Vec<f64> = a.readonly().as_array().iter().copied().collect();
    check_finite(name, &flat, cols)?;
    Ok(flat.chunks(cols).map(|c| c.to_vec()).collect())
}

/// A finite number.
pub fn finite(name: &str, x: f64) -> PyResult<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(NonFiniteError::new_err(format!(
            "{name} = {x} is not finite"
        )))
    }
}
