//! Compiling an [`Expr`] once into a straight-line tape, and evaluating the tape generically
//! over the scalar (f64, or num-dual's first- and second-order dual numbers for exact
//! derivatives).
//!
//! Compilation resolves names (parameters and `pi` become numbers), folds constants
//! (`2*lambda/3` is one number; `x^2` becomes a square, `x^3` an integer power, `x/2` a
//! division by a constant), and reuses common subexpressions by hash-consing: two equal
//! operations on equal operands share one slot, so `cos(x - y)` written twice is computed once.
//! Evaluation is one pass over the tape into a stack buffer (no allocation up to 384 slots).

use super::parse::{BinOp, Expr, Func};
use crate::error::{ExpressionError, Position};
use num_dual::DualNum;
use std::collections::HashMap;

/// What a name stands for when an expression is compiled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Symbol {
    /// Entry i of the first argument of [`Tape::eval`] (the coordinates q).
    Q(u32),
    /// Entry i of the second argument of [`Tape::eval`] (the velocities v).
    V(u32),
    /// A number (a parameter or a constant).
    Value(f64),
}

/// One instruction; operands are slot indices (always earlier slots).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    Q(u32),
    V(u32),
    Const(f64),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Pow(u32, u32),
    Atan2(u32, u32),
    AddC(u32, f64),
    MulC(u32, f64),
    DivC(u32, f64),
    CSub(f64, u32),
    CDiv(f64, u32),
    Neg(u32),
    Square(u32),
    Powi(u32, i32),
    Powf(u32, f64),
    Unary(Func, u32),
}

impl Op {
    /// A hashable identity for common-subexpression reuse.
    fn key(&self) -> (u8, u32, u64) {
        let f = |x: f64| x.to_bits();
        match *self {
            Op::Q(i) => (0, i, 0),
            Op::V(i) => (1, i, 0),
            Op::Const(c) => (2, 0, f(c)),
            Op::Add(a, b) => (3, a, b as u64),
            Op::Sub(a, b) => (4, a, b as u64),
            Op::Mul(a, b) => (5, a, b as u64),
            Op::Div(a, b) => (6, a, b as u64),
            Op::Pow(a, b) => (7, a, b as u64),
            Op::Atan2(a, b) => (8, a, b as u64),
            Op::AddC(a, c) => (9, a, f(c)),
            Op::MulC(a, c) => (10, a, f(c)),
            Op::DivC(a, c) => (11, a, f(c)),
            Op::CSub(c, a) => (12, a, f(c)),
            Op::CDiv(c, a) => (13, a, f(c)),
            Op::Neg(a) => (14, a, 0),
            Op::Square(a) => (15, a, 0),
            Op::Powi(a, i) => (16, a, i as u32 as u64),
            Op::Powf(a, e) => (17, a, f(e)),
            Op::Unary(func, a) => (18 + func as u8, a, 0),
        }
    }
}

#[inline(always)]
fn unary<T: DualNum<Primitive = f64> + Copy>(func: Func, a: T) -> T {
    match func {
        Func::Sin => a.sin(),
        Func::Cos => a.cos(),
        Func::Tan => a.tan(),
        Func::Exp => a.exp(),
        Func::Log => a.ln(),
        Func::Sqrt => a.sqrt(),
        Func::Abs => a.abs(),
        Func::Sinh => a.sinh(),
        Func::Cosh => a.cosh(),
        Func::Tanh => a.tanh(),
        // Two-argument functions are their own instructions; never emitted as `Unary`.
        Func::Pow | Func::Atan2 => T::from(f64::NAN),
    }
}

/// a^e for a constant exponent, with the same special forms as at run time (square, square
/// root, integer power), so that folding a constant base gives the value a variable one would.
fn constant_power(a: f64, e: f64) -> f64 {
    if e == 1.0 {
        a
    } else if e == 0.0 {
        1.0
    } else if e == 2.0 {
        a * a
    } else if e == 0.5 {
        a.sqrt()
    } else if e.fract() == 0.0 && e.abs() <= 64.0 {
        a.powi(e as i32)
    } else {
        a.powf(e)
    }
}

/// A compiled expression: straight-line code over slots, the result in the last slot.
#[derive(Debug, Clone, PartialEq)]
pub struct Tape {
    ops: Vec<Op>,
}

/// A compiled value: known at compile time, or computed in a slot.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Node {
    Const(f64),
    Slot(u32),
}

struct Compiler<'a> {
    text: &'a str,
    symbols: &'a [(String, Symbol)],
    ops: Vec<Op>,
    seen: HashMap<(u8, u32, u64), u32>,
}

impl Tape {
    /// Compile `expr` (parsed from `text`, which positions in errors refer to) with the
    /// given meaning of each name. An unknown name is [`ExpressionError::UnknownSymbol`].
    pub(crate) fn compile(
        expr: &Expr,
        text: &str,
        symbols: &[(String, Symbol)],
    ) -> Result<Tape, ExpressionError> {
        let mut c = Compiler {
            text,
            symbols,
            ops: Vec::new(),
            seen: HashMap::new(),
        };
        let root = c.node(expr)?;
        let root = c.slot(root);
        // The result must be the last slot: re-emit it if CSE returned an earlier one.
        if root as usize + 1 != c.ops.len() {
            c.ops.push(Op::AddC(root, 0.0));
        }
        Ok(Tape { ops: c.ops })
    }

    /// Number of instructions after folding and common-subexpression reuse.
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Whether the tape is empty (never, for a compiled expression).
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Whether the expression reads the coordinate slot `i` (slot D is the time `t`).
    pub(crate) fn reads_q(&self, i: usize) -> bool {
        self.ops.contains(&Op::Q(i as u32))
    }

    /// Whether the expression reads the velocity `i`.
    pub(crate) fn reads_v(&self, i: usize) -> bool {
        self.ops.contains(&Op::V(i as u32))
    }

    /// Evaluate at (q, v), generic over the scalar. Entries missing from `q` or `v` read as
    /// NaN (the callers pass the system's dimension; this only keeps misuse from panicking).
    #[inline]
    pub fn eval<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let zero = T::from(0.0);
        match self.ops.len() {
            n if n <= 24 => self.run(&mut [zero; 24], q, v),
            n if n <= 96 => self.run(&mut [zero; 96], q, v),
            n if n <= 384 => self.run(&mut [zero; 384], q, v),
            n => self.run(&mut vec![zero; n], q, v),
        }
    }

    #[inline(always)]
    fn run<T: DualNum<Primitive = f64> + Copy>(&self, s: &mut [T], q: &[T], v: &[T]) -> T {
        let nan = T::from(f64::NAN);
        let mut last = nan;
        for (k, op) in self.ops.iter().enumerate() {
            let x = match *op {
                Op::Q(i) => q.get(i as usize).copied().unwrap_or(nan),
                Op::V(i) => v.get(i as usize).copied().unwrap_or(nan),
                Op::Const(c) => T::from(c),
                Op::Add(a, b) => s[a as usize] + s[b as usize],
                Op::Sub(a, b) => s[a as usize] - s[b as usize],
                Op::Mul(a, b) => s[a as usize] * s[b as usize],
                Op::Div(a, b) => s[a as usize] / s[b as usize],
                Op::Pow(a, b) => s[a as usize].powd(s[b as usize]),
                Op::Atan2(a, b) => s[a as usize].atan2(s[b as usize]),
                Op::AddC(a, c) => s[a as usize] + c,
                Op::MulC(a, c) => s[a as usize] * c,
                Op::DivC(a, c) => s[a as usize] / c,
                Op::CSub(c, a) => -s[a as usize] + c,
                Op::CDiv(c, a) => T::from(c) / s[a as usize],
                Op::Neg(a) => -s[a as usize],
                Op::Square(a) => s[a as usize] * s[a as usize],
                Op::Powi(a, i) => s[a as usize].powi(i),
                Op::Powf(a, e) => s[a as usize].powf(e),
                Op::Unary(f, a) => unary(f, s[a as usize]),
            };
            s[k] = x;
            last = x;
        }
        last
    }
}

impl Compiler<'_> {
    fn emit(&mut self, op: Op) -> Node {
        let key = op.key();
        if let Some(&slot) = self.seen.get(&key) {
            return Node::Slot(slot);
        }
        let slot = self.ops.len() as u32;
        self.ops.push(op);
        self.seen.insert(key, slot);
        Node::Slot(slot)
    }

    fn slot(&mut self, n: Node) -> u32 {
        match n {
            Node::Slot(s) => s,
            Node::Const(c) => match self.emit(Op::Const(c)) {
                Node::Slot(s) => s,
                Node::Const(_) => 0, // `emit` always returns a slot
            },
        }
    }

    fn node(&mut self, e: &Expr) -> Result<Node, ExpressionError> {
        Ok(match e {
            Expr::Num(x) => Node::Const(*x),
            Expr::Sym { name, at } => match self.symbols.iter().find(|(n, _)| n == name) {
                Some((_, Symbol::Value(x))) => Node::Const(*x),
                Some((_, Symbol::Q(i))) => self.emit(Op::Q(*i)),
                Some((_, Symbol::V(i))) => self.emit(Op::V(*i)),
                None => {
                    return Err(ExpressionError::UnknownSymbol {
                        name: name.clone(),
                        at: Position::locate(self.text, *at),
                        known: self.symbols.iter().map(|(n, _)| n.clone()).collect(),
                    });
                }
            },
            Expr::Neg(a) => match self.node(a)? {
                Node::Const(c) => Node::Const(-c),
                Node::Slot(s) => self.emit(Op::Neg(s)),
            },
            Expr::Bin(op, a, b) => {
                let (a, b) = (self.node(a)?, self.node(b)?);
                self.binary(*op, a, b)
            }
            Expr::Call(func, args) => match (func, args.as_slice()) {
                (Func::Pow, [a, b]) => {
                    let (a, b) = (self.node(a)?, self.node(b)?);
                    self.binary(BinOp::Pow, a, b)
                }
                (Func::Atan2, [a, b]) => match (self.node(a)?, self.node(b)?) {
                    (Node::Const(y), Node::Const(x)) => Node::Const(y.atan2(x)),
                    (a, b) => {
                        let (a, b) = (self.slot(a), self.slot(b));
                        self.emit(Op::Atan2(a, b))
                    }
                },
                (f, [a]) => match self.node(a)? {
                    Node::Const(c) => Node::Const(unary(*f, c)),
                    Node::Slot(s) => self.emit(Op::Unary(*f, s)),
                },
                // The parser checks arities; a hand-built tree with a wrong one is NaN.
                _ => Node::Const(f64::NAN),
            },
        })
    }

    /// Emit a ∘ b with constant folding and the cheap special forms.
    fn binary(&mut self, op: BinOp, a: Node, b: Node) -> Node {
        use Node::{Const, Slot};
        match (op, a, b) {
            (BinOp::Add, Const(x), Const(y)) => Const(x + y),
            (BinOp::Sub, Const(x), Const(y)) => Const(x - y),
            (BinOp::Mul, Const(x), Const(y)) => Const(x * y),
            (BinOp::Div, Const(x), Const(y)) => Const(x / y),
            (BinOp::Pow, Const(x), Const(y)) => Const(constant_power(x, y)),

            (BinOp::Add, Slot(s), Const(c)) | (BinOp::Add, Const(c), Slot(s)) => {
                if c == 0.0 {
                    Slot(s)
                } else {
                    self.emit(Op::AddC(s, c))
                }
            }
            (BinOp::Add, Slot(s), Slot(t)) => self.emit(Op::Add(s.min(t), s.max(t))),
            (BinOp::Sub, Slot(s), Const(c)) => {
                if c == 0.0 {
                    Slot(s)
                } else {
                    self.emit(Op::AddC(s, -c))
                }
            }
            (BinOp::Sub, Const(c), Slot(s)) => {
                if c == 0.0 {
                    self.emit(Op::Neg(s))
                } else {
                    self.emit(Op::CSub(c, s))
                }
            }
            (BinOp::Sub, Slot(s), Slot(t)) => self.emit(Op::Sub(s, t)),
            (BinOp::Mul, Slot(s), Const(c)) | (BinOp::Mul, Const(c), Slot(s)) => {
                if c == 1.0 {
                    Slot(s)
                } else if c == -1.0 {
                    self.emit(Op::Neg(s))
                } else {
                    self.emit(Op::MulC(s, c))
                }
            }
            (BinOp::Mul, Slot(s), Slot(t)) if s == t => self.emit(Op::Square(s)),
            (BinOp::Mul, Slot(s), Slot(t)) => self.emit(Op::Mul(s.min(t), s.max(t))),
            (BinOp::Div, Slot(s), Const(c)) => {
                if c == 1.0 {
                    Slot(s)
                } else {
                    self.emit(Op::DivC(s, c))
                }
            }
            (BinOp::Div, Const(c), Slot(s)) => self.emit(Op::CDiv(c, s)),
            (BinOp::Div, Slot(s), Slot(t)) => self.emit(Op::Div(s, t)),
            (BinOp::Pow, Slot(s), Const(e)) => {
                if e == 1.0 {
                    Slot(s)
                } else if e == 0.0 {
                    Const(1.0)
                } else if e == 2.0 {
                    self.emit(Op::Square(s))
                } else if e == 0.5 {
                    self.emit(Op::Unary(Func::Sqrt, s))
                } else if e.fract() == 0.0 && e.abs() <= 64.0 {
                    self.emit(Op::Powi(s, e as i32))
                } else {
                    self.emit(Op::Powf(s, e))
                }
            }
            (BinOp::Pow, a, b) => {
                let (a, b) = (self.slot(a), self.slot(b));
                self.emit(Op::Pow(a, b))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::parse::parse;
    use super::*;

    fn tape(text: &str) -> Tape {
        let symbols = [
            ("x".to_string(), Symbol::Q(0)),
            ("y".to_string(), Symbol::Q(1)),
            ("x_dot".to_string(), Symbol::V(0)),
            ("k".to_string(), Symbol::Value(3.0)),
        ];
        Tape::compile(&parse(text).unwrap(), text, &symbols).unwrap()
    }

    #[test]
    fn folds_constants_and_reuses_subexpressions() {
        // x, y, x−y, cos(x−y), its square, the sum: six slots; 2*k/3 folded to 2.
        let t = tape("cos(x - y)^2 + cos(x-y) * (2*k/3)");
        assert_eq!(t.len(), 7, "{:?}", t.ops);
        let (x, y) = (0.3f64, -1.1f64);
        let c = (x - y).cos();
        assert_eq!(t.eval(&[x, y], &[]), c * c + c * 2.0);
        let t = tape("k*k - 9");
        assert_eq!((t.len(), t.eval::<f64>(&[], &[])), (1, 0.0));
        let t = tape("x_dot^3 - x_dot^2/2 + 2^x + pow(y, x) + atan2(y, x) + x^0.5 + x^1.5");
        let (x, y, v) = (0.7f64, 1.3f64, -0.4f64);
        let exact = v.powi(3) - v * v / 2.0
            + 2f64.powf(x)
            + y.powf(x)
            + y.atan2(x)
            + x.sqrt()
            + x.powf(1.5);
        assert!((t.eval(&[x, y], &[v]) - exact).abs() < 1e-15);
    }

    #[test]
    fn dual_numbers_give_exact_derivatives() {
        use num_dual::Dual64;
        let t = tape("sin(x)*exp(y) + log(x)*tanh(y) + sqrt(x)*abs(y) - sinh(x)/cosh(y) + tan(x)");
        let (x, y) = (0.6f64, -0.8f64);
        let d = t.eval(&[Dual64::from(x).derivative(), Dual64::from(y)], &[]);
        let exact = x.cos() * y.exp() + y.tanh() / x + 0.5 / x.sqrt() * y.abs()
            - x.cosh() / y.cosh()
            + 1.0 / x.cos().powi(2);
        assert!((d.eps - exact).abs() < 1e-14, "{} vs {exact}", d.eps);
    }
}
