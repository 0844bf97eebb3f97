//! Event functions written as expressions: g(t, q, p) from text, for scene files, the
//! command line (`gvi section --event`) and Python.

use super::EventFunction;
use crate::error::{ExpressionError, Result};
use crate::systems::expression::{Tape, parse};

/// An event function g(t, q, p) given as an expression over the coordinate names, the
/// momenta `p_<name>` (the canonical momentum of coordinate `name`), the time `t`, the
/// parameters and `pi`.
///
/// ```
/// use galerkin_vi::events::{EventFunction, ExpressionEvent};
///
/// // The section x = 0 of a system with coordinates (x, y).
/// let g = ExpressionEvent::parse("x", &["x", "y"], &[])?;
/// assert_eq!(g.value(0.0, &[0.25, 1.0], &[0.0, 0.0]), 0.25);
/// // A stroboscopic event: zero at t = 2πk/ω.
/// let strobe = ExpressionEvent::parse("sin(omega*t/2)", &["x"], &[("omega", 1.2)])?;
/// assert!(strobe.value(std::f64::consts::TAU / 1.2, &[0.0], &[0.0]).abs() < 1e-15);
/// // p_y is the momentum of y.
/// let h = ExpressionEvent::parse("p_y - 0.5", &["x", "y"], &[])?;
/// assert_eq!(h.value(0.0, &[0.0, 0.0], &[1.0, 0.5]), 0.0);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ExpressionEvent {
    text: String,
    tape: Tape,
    dim: usize,
}

impl ExpressionEvent {
    /// Compile `text` over `coordinates` (momenta `p_<name>`), `t` and `parameters`.
    ///
    /// Errors: syntax errors (with position), unknown symbols (listing the known ones), a
    /// parameter named like a coordinate, a momentum, `t` or `pi`, a non-finite parameter.
    pub fn parse(text: &str, coordinates: &[&str], parameters: &[(&str, f64)]) -> Result<Self> {
        use crate::systems::expression::Symbol;
        let d = coordinates.len();
        let mut symbols: Vec<(String, Symbol)> = Vec::new();
        for (i, c) in coordinates.iter().enumerate() {
            symbols.push((c.to_string(), Symbol::Q(i as u32)));
            symbols.push((format!("p_{c}"), Symbol::V(i as u32)));
        }
        symbols.push(("t".into(), Symbol::Q(d as u32)));
        symbols.push(("pi".into(), Symbol::Value(std::f64::consts::PI)));
        for &(name, value) in parameters {
            if symbols.iter().any(|(n, _)| n == name) {
                return Err(ExpressionError::InvalidName {
                    name: name.to_string(),
                    reason: "a parameter cannot reuse a coordinate, momentum, t or pi".into(),
                }
                .into());
            }
            if !value.is_finite() {
                return Err(ExpressionError::NonFiniteParameter {
                    name: name.to_string(),
                    value,
                }
                .into());
            }
            symbols.push((name.to_string(), Symbol::Value(value)));
        }
        let tape = Tape::compile(&parse(text)?, text, &symbols)?;
        Ok(ExpressionEvent {
            text: text.to_string(),
            tape,
            dim: d,
        })
    }

    /// The source text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The number of coordinates it was compiled for.
    pub fn dim(&self) -> usize {
        self.dim
    }
}

impl EventFunction for ExpressionEvent {
    fn value(&self, t: f64, q: &[f64], p: &[f64]) -> f64 {
        // (q, t) in one buffer: t is the slot after the coordinates.
        let d = q.len();
        let mut stack = [0.0; 65];
        let mut heap;
        let qt: &mut [f64] = if d < stack.len() {
            &mut stack[..d + 1]
        } else {
            heap = vec![0.0; d + 1];
            &mut heap
        };
        qt[..d].copy_from_slice(q);
        qt[d] = t;
        self.tape.eval(qt, p)
    }
}
