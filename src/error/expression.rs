//! Typed errors of expression Lagrangians: where in the text, and what was expected.

use std::fmt;

/// A place in an expression's text: 1-based line and column (in characters), with the line
/// itself so that messages can print a caret under the spot.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Position {
    /// 1-based line.
    pub line: usize,
    /// 1-based column, counted in characters.
    pub column: usize,
    /// The text of that line.
    pub source_line: String,
}

impl Position {
    /// The position of byte offset `at` in `text` (clamped to the text).
    pub fn locate(text: &str, at: usize) -> Position {
        let mut at = at.min(text.len());
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        let before = &text[..at];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let line_end = text[at..].find('\n').map_or(text.len(), |i| at + i);
        Position {
            line: before.matches('\n').count() + 1,
            column: text[line_start..at].chars().count() + 1,
            source_line: text[line_start..line_end]
                .trim_end_matches('\r')
                .to_string(),
        }
    }
}

impl ExpressionError {
    /// This error, as an error in the expression `what` ([`ExpressionError::In`]).
    pub fn within(self, what: impl Into<String>) -> ExpressionError {
        ExpressionError::In {
            what: what.into(),
            source: Box::new(self),
        }
    }
}

/// The source line and a caret under the column (tabs kept so that the caret lines up).
impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pad: String = self
            .source_line
            .chars()
            .take(self.column - 1)
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        let missing = (self.column - 1).saturating_sub(pad.chars().count());
        write!(f, "{}\n{pad}{}^", self.source_line, " ".repeat(missing))
    }
}

/// Why an expression Lagrangian was rejected.
///
/// An error in one of the expressions given with it (the exact solution, the force) is
/// [`ExpressionError::In`], which names the expression:
///
/// ```
/// use galerkin_vi::systems::ExpressionLagrangian;
/// let l = ExpressionLagrangian::parse("x_dot^2/2 - x^2/2", &["x"], &[])?;
/// let e = l.with_exact_solution(&["..."]).unwrap_err().to_string();
/// assert!(e.starts_with("`exact` entry 1 of 1 (q(t) of `x`): syntax error"), "{e}");
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExpressionError {
    /// The text does not parse.
    #[error("syntax error at line {}, column {}: {message}\n{at}", at.line, at.column)]
    Syntax {
        /// Where.
        at: Position,
        /// What was expected or found.
        message: String,
    },
    /// A name that is neither a coordinate, a velocity, a parameter nor `pi`.
    #[error(
        "unknown symbol `{name}` at line {}, column {}; known symbols: {}\n{at}",
        at.line, at.column, known.join(", ")
    )]
    UnknownSymbol {
        /// The name.
        name: String,
        /// Where it is first used.
        at: Position,
        /// The names that are known (coordinates, velocities, parameters, constants).
        known: Vec<String>,
    },
    /// A call of a function that does not exist.
    #[error(
        "unknown function `{name}` at line {}, column {}; known functions: {}\n{at}",
        at.line, at.column, known.join(", ")
    )]
    UnknownFunction {
        /// The name.
        name: String,
        /// Where.
        at: Position,
        /// The known functions.
        known: Vec<String>,
    },
    /// A coordinate whose velocity does not occur in the Lagrangian: L would not depend on
    /// q̇ for it, so ∂²L/∂q̇² is singular everywhere.
    #[error(
        "coordinate `{coordinate}` has no velocity: `{coordinate}_dot` does not occur in the \
         Lagrangian, so it is degenerate (∂²L/∂v² singular)"
    )]
    MissingVelocity {
        /// The coordinate.
        coordinate: String,
    },
    /// A coordinate or parameter name that cannot be used.
    #[error("invalid name `{name}`: {reason}")]
    InvalidName {
        /// The name.
        name: String,
        /// Why.
        reason: String,
    },
    /// A parameter that is NaN or infinite.
    #[error("parameter `{name}` = {value} is not finite")]
    NonFiniteParameter {
        /// The parameter.
        name: String,
        /// Its value.
        value: f64,
    },
    /// The velocity Hessian ∂²L/∂v∂v is singular (or not finite) at the state: the
    /// Lagrangian is not regular there, and p = ∂L/∂v does not determine v.
    #[error(
        "the Lagrangian is not regular at {what}: the velocity Hessian ∂²L/∂v∂v at q = {q:?}, \
         v = {v:?} is singular (reciprocal condition number {rcond:.2e}), so the momenta do \
         not determine the velocities"
    )]
    SingularHessian {
        /// Which state (e.g. "the initial state").
        what: String,
        /// Configuration.
        q: Vec<f64>,
        /// Velocity.
        v: Vec<f64>,
        /// Reciprocal condition number min|λ|/max|λ| of ∂²L/∂v∂v (0 if not finite).
        rcond: f64,
    },
    /// An error in an expression that goes with the Lagrangian (an entry of the exact
    /// solution `exact` or of the force `force`), naming that expression rather than the
    /// Lagrangian: `` `exact` entry 1 of 2 (q(t) of `x`): syntax error at line 1, … ``.
    #[error("{what}: {source}")]
    In {
        /// Which expression (`` `exact` entry 1 of 2 (q(t) of `x`) ``).
        what: String,
        /// The error in it.
        source: Box<ExpressionError>,
    },
    /// Newton's method for the inverse Legendre transform p = ∂L/∂v(q, v) did not converge.
    #[error(
        "no velocity found for the momentum p = {p:?} at q = {q:?}: damped Newton iteration on \
         p = ∂L/∂v did not converge (residual max|p − ∂L/∂v| = {residual:.2e} after \
         {iterations} iterations)"
    )]
    Legendre {
        /// Configuration.
        q: Vec<f64>,
        /// Momentum.
        p: Vec<f64>,
        /// Max-norm of p − ∂L/∂v at the last iterate.
        residual: f64,
        /// Newton iterations taken.
        iterations: usize,
    },
}
