//! The expression language of scene-file Lagrangians: a hand-written precedence-climbing
//! parser into an [`Expr`] tree, and printing back to text that parses to the same tree.
//!
//! Grammar (lowest precedence first; `^` is right-associative and binds tighter than unary
//! minus, so `-x^2 = -(x^2)` and `2^-1 = 0.5`, as in mathematics):
//!
//! ```text
//! sum     = product (("+" | "-") product)*
//! product = unary (("*" | "/") unary)*
//! unary   = ("-" | "+") unary | power
//! power   = atom ("^" unary)?
//! atom    = number | name | name "(" sum ("," sum)* ")" | "(" sum ")"
//! ```

use crate::error::{ExpressionError, Position};
use std::fmt;

/// The deepest tree accepted (a sum of k terms is k levels deep): deeper trees are a syntax
/// error, so that no recursion over a tree (compiling, printing, dropping) can exhaust even a
/// 2 MiB thread stack.
pub const MAX_DEPTH: usize = 1000;

/// A built-in function.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Func {
    /// sin x
    Sin,
    /// cos x
    Cos,
    /// tan x
    Tan,
    /// eˣ
    Exp,
    /// Natural logarithm.
    Log,
    /// √x
    Sqrt,
    /// |x|
    Abs,
    /// sinh x
    Sinh,
    /// cosh x
    Cosh,
    /// tanh x
    Tanh,
    /// pow(x, y) = x^y
    Pow,
    /// atan2(y, x), the angle of the point (x, y)
    Atan2,
}

impl Func {
    /// Every function, in the order listed in error messages.
    pub const ALL: [Func; 12] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Exp,
        Func::Log,
        Func::Sqrt,
        Func::Abs,
        Func::Pow,
        Func::Atan2,
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
    ];

    /// The name used in expressions.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Log => "log",
            Func::Sqrt => "sqrt",
            Func::Abs => "abs",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
            Func::Tanh => "tanh",
            Func::Pow => "pow",
            Func::Atan2 => "atan2",
        }
    }

    /// Number of arguments.
    pub fn arity(self) -> usize {
        match self {
            Func::Pow | Func::Atan2 => 2,
            _ => 1,
        }
    }

    /// The function of this name, if any.
    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinOp {
    /// a + b
    Add,
    /// a − b
    Sub,
    /// a · b
    Mul,
    /// a / b
    Div,
    /// a ^ b
    Pow,
}

impl BinOp {
    fn symbol(self) -> char {
        match self {
            BinOp::Add => '+',
            BinOp::Sub => '-',
            BinOp::Mul => '*',
            BinOp::Div => '/',
            BinOp::Pow => '^',
        }
    }

    fn precedence(self) -> u8 {
        match self {
            BinOp::Add | BinOp::Sub => 1,
            BinOp::Mul | BinOp::Div => 2,
            BinOp::Pow => 4,
        }
    }
}

/// Precedence of unary minus (between `*` and `^`) and of atoms.
const NEG: u8 = 3;
const ATOM: u8 = 5;

/// An expression tree. Symbols keep the byte offset where they were written, so that an
/// unknown name is reported at its line and column; equality ignores the offsets.
#[derive(Debug, Clone)]
pub enum Expr {
    /// A non-negative number literal (a leading minus is [`Expr::Neg`]).
    Num(f64),
    /// A name: a coordinate, a velocity (`x_dot`), a parameter or `pi`.
    Sym {
        /// The name.
        name: String,
        /// Byte offset in the source text.
        at: usize,
    },
    /// −a
    Neg(Box<Expr>),
    /// a ∘ b
    Bin(BinOp, Box<Expr>, Box<Expr>),
    /// f(a) or f(a, b)
    Call(Func, Vec<Expr>),
}

impl PartialEq for Expr {
    fn eq(&self, other: &Expr) -> bool {
        match (self, other) {
            (Expr::Num(a), Expr::Num(b)) => a.to_bits() == b.to_bits(),
            (Expr::Sym { name: a, .. }, Expr::Sym { name: b, .. }) => a == b,
            (Expr::Neg(a), Expr::Neg(b)) => a == b,
            (Expr::Bin(o, a, b), Expr::Bin(p, c, d)) => o == p && a == c && b == d,
            (Expr::Call(f, a), Expr::Call(g, b)) => f == g && a == b,
            _ => false,
        }
    }
}

impl Expr {
    fn precedence(&self) -> u8 {
        match self {
            Expr::Num(_) | Expr::Sym { .. } | Expr::Call(..) => ATOM,
            Expr::Neg(_) => NEG,
            Expr::Bin(op, ..) => op.precedence(),
        }
    }

    /// Visit every symbol with its byte offset.
    pub fn for_each_symbol(&self, f: &mut impl FnMut(&str, usize)) {
        match self {
            Expr::Num(_) => {}
            Expr::Sym { name, at } => f(name, *at),
            Expr::Neg(a) => a.for_each_symbol(f),
            Expr::Bin(_, a, b) => {
                a.for_each_symbol(f);
                b.for_each_symbol(f);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.for_each_symbol(f)),
        }
    }
}

/// Prints with the fewest parentheses that parse back to the same tree (numbers in Rust's
/// shortest round-trip form, in exponent notation when long, so `parse(print(e)) == e`
/// exactly).
impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn wrap(f: &mut fmt::Formatter<'_>, e: &Expr, parens: bool) -> fmt::Result {
            if parens {
                write!(f, "({e})")
            } else {
                write!(f, "{e}")
            }
        }
        match self {
            Expr::Num(x) => {
                let plain = format!("{x}");
                if plain.len() > 24 {
                    write!(f, "{x:e}")
                } else {
                    f.write_str(&plain)
                }
            }
            Expr::Sym { name, .. } => f.write_str(name),
            Expr::Neg(a) => {
                f.write_str("-")?;
                wrap(f, a, a.precedence() <= NEG)
            }
            Expr::Bin(op, a, b) => {
                let p = op.precedence();
                // `^` is right-associative: its left operand needs parentheses at equal
                // precedence, and its right operand is a unary (parenthesised if signed).
                let left = match op {
                    BinOp::Pow => a.precedence() <= p,
                    _ => a.precedence() < p,
                };
                let right = match op {
                    BinOp::Pow => b.precedence() < p,
                    _ => b.precedence() <= p,
                };
                wrap(f, a, left)?;
                write!(f, "{}", op.symbol())?;
                wrap(f, b, right)
            }
            Expr::Call(func, args) => {
                write!(f, "{}(", func.name())?;
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{a}")?;
                }
                f.write_str(")")
            }
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Num(f64),
    Name(String),
    Op(char),
    LParen,
    RParen,
    Comma,
    End,
}

fn describe(t: &Token) -> String {
    match t {
        Token::Num(x) => format!("number {x}"),
        Token::Name(n) => format!("name `{n}`"),
        Token::Op(c) => format!("`{c}`"),
        Token::LParen => "`(`".into(),
        Token::RParen => "`)`".into(),
        Token::Comma => "`,`".into(),
        Token::End => "end of expression".into(),
    }
}

struct Parser<'a> {
    text: &'a str,
    tokens: Vec<(Token, usize)>,
    pos: usize,
}

fn lex(text: &str) -> Result<Vec<(Token, usize)>, ExpressionError> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if c.is_ascii_digit() || c == b'.' {
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                let mut j = i + 1;
                if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                    j += 1;
                }
                if j < bytes.len() && bytes[j].is_ascii_digit() {
                    while j < bytes.len() && bytes[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                } else {
                    return Err(syntax(text, j.min(bytes.len()), "exponent without digits"));
                }
            }
            let literal = &text[start..i];
            match literal.parse::<f64>() {
                Ok(x) if x.is_finite() => out.push((Token::Num(x), start)),
                Ok(_) => return Err(syntax(text, start, "number out of range")),
                Err(_) => {
                    return Err(syntax(
                        text,
                        start,
                        &format!("malformed number `{literal}`"),
                    ));
                }
            }
            continue;
        }
        if c.is_ascii_alphabetic() || c == b'_' {
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            out.push((Token::Name(text[start..i].to_string()), start));
            continue;
        }
        let token = match c {
            b'+' | b'-' | b'*' | b'/' | b'^' => Token::Op(c as char),
            b'(' => Token::LParen,
            b')' => Token::RParen,
            b',' => Token::Comma,
            _ => {
                let ch = text[start..].chars().next().unwrap_or('?');
                return Err(syntax(
                    text,
                    start,
                    &format!("unexpected character `{ch}` (operators are + - * / ^)"),
                ));
            }
        };
        out.push((token, start));
        i += 1;
    }
    out.push((Token::End, text.len()));
    Ok(out)
}

fn syntax(text: &str, at: usize, message: &str) -> ExpressionError {
    ExpressionError::Syntax {
        at: Position::locate(text, at),
        message: message.to_string(),
    }
}

/// Parse an expression. Names are not resolved here (see
/// [`ExpressionLagrangian::parse`](super::ExpressionLagrangian::parse)); functions are, and a
/// wrong number of arguments is a syntax error.
///
/// ```
/// use galerkin_vi::systems::expression::parse;
/// let e = parse("-x^2 + 2*sin(y)").unwrap();
/// assert_eq!(e.to_string(), "-x^2+2*sin(y)");
/// let err = parse("x + * y").unwrap_err().to_string();
/// assert!(err.contains("line 1, column 5"), "{err}");
/// ```
pub fn parse(text: &str) -> Result<Expr, ExpressionError> {
    let tokens = lex(text)?;
    let mut p = Parser {
        text,
        tokens,
        pos: 0,
    };
    let (e, _) = p.sum(0)?;
    match p.peek() {
        (Token::End, _) => Ok(e),
        (Token::RParen, at) => Err(syntax(text, at, "unmatched `)`")),
        (t, at) => Err(syntax(
            text,
            at,
            &format!("expected an operator, found {}", describe(&t)),
        )),
    }
}

impl Parser<'_> {
    fn peek(&self) -> (Token, usize) {
        let (t, at) = &self.tokens[self.pos.min(self.tokens.len() - 1)];
        (t.clone(), *at)
    }

    fn bump(&mut self) {
        if self.pos + 1 < self.tokens.len() {
            self.pos += 1;
        }
    }

    fn check_depth(&self, depth: usize, at: usize) -> Result<(), ExpressionError> {
        if depth > MAX_DEPTH {
            Err(syntax(
                self.text,
                at,
                &format!("expression nested deeper than {MAX_DEPTH} levels"),
            ))
        } else {
            Ok(())
        }
    }

    fn binary(
        &self,
        op: BinOp,
        (a, da): (Expr, usize),
        (b, db): (Expr, usize),
        at: usize,
    ) -> Result<(Expr, usize), ExpressionError> {
        let depth = da.max(db) + 1;
        self.check_depth(depth, at)?;
        Ok((Expr::Bin(op, Box::new(a), Box::new(b)), depth))
    }

    fn sum(&mut self, nest: usize) -> Result<(Expr, usize), ExpressionError> {
        let mut left = self.product(nest)?;
        loop {
            let (t, at) = self.peek();
            let op = match t {
                Token::Op('+') => BinOp::Add,
                Token::Op('-') => BinOp::Sub,
                _ => return Ok(left),
            };
            self.bump();
            let right = self.product(nest)?;
            left = self.binary(op, left, right, at)?;
        }
    }

    fn product(&mut self, nest: usize) -> Result<(Expr, usize), ExpressionError> {
        let mut left = self.unary(nest)?;
        loop {
            let (t, at) = self.peek();
            let op = match t {
                Token::Op('*') => BinOp::Mul,
                Token::Op('/') => BinOp::Div,
                _ => return Ok(left),
            };
            self.bump();
            let right = self.unary(nest)?;
            left = self.binary(op, left, right, at)?;
        }
    }

    fn unary(&mut self, nest: usize) -> Result<(Expr, usize), ExpressionError> {
        let (t, at) = self.peek();
        self.check_depth(nest, at)?;
        match t {
            Token::Op('-') => {
                self.bump();
                let (e, d) = self.unary(nest + 1)?;
                self.check_depth(d + 1, at)?;
                Ok((Expr::Neg(Box::new(e)), d + 1))
            }
            Token::Op('+') => {
                self.bump();
                self.unary(nest + 1)
            }
            _ => self.power(nest),
        }
    }

    fn power(&mut self, nest: usize) -> Result<(Expr, usize), ExpressionError> {
        let base = self.atom(nest)?;
        let (t, at) = self.peek();
        if t == Token::Op('^') {
            self.bump();
            let exponent = self.unary(nest + 1)?;
            return self.binary(BinOp::Pow, base, exponent, at);
        }
        Ok(base)
    }

    fn atom(&mut self, nest: usize) -> Result<(Expr, usize), ExpressionError> {
        let (t, at) = self.peek();
        match t {
            Token::Num(x) => {
                self.bump();
                Ok((Expr::Num(x), 0))
            }
            Token::Name(name) => {
                self.bump();
                if self.peek().0 != Token::LParen {
                    return Ok((Expr::Sym { name, at }, 0));
                }
                let Some(func) = Func::from_name(&name) else {
                    return Err(ExpressionError::UnknownFunction {
                        name,
                        at: Position::locate(self.text, at),
                        known: Func::ALL.iter().map(|f| f.name().to_string()).collect(),
                    });
                };
                self.bump();
                let mut args = Vec::new();
                let mut depth = 0;
                loop {
                    let (a, d) = self.sum(nest + 1)?;
                    args.push(a);
                    depth = depth.max(d + 1);
                    match self.peek() {
                        (Token::Comma, _) => self.bump(),
                        (Token::RParen, _) => {
                            self.bump();
                            break;
                        }
                        (t, p) => {
                            return Err(syntax(
                                self.text,
                                p,
                                &format!(
                                    "expected `,` or `)` in {name}(…), found {}",
                                    describe(&t)
                                ),
                            ));
                        }
                    }
                }
                if args.len() != func.arity() {
                    return Err(syntax(
                        self.text,
                        at,
                        &format!(
                            "{name} takes {} argument{}, given {}",
                            func.arity(),
                            if func.arity() == 1 { "" } else { "s" },
                            args.len()
                        ),
                    ));
                }
                self.check_depth(depth, at)?;
                Ok((Expr::Call(func, args), depth))
            }
            Token::LParen => {
                self.bump();
                let inner = self.sum(nest + 1)?;
                match self.peek() {
                    (Token::RParen, _) => {
                        self.bump();
                        Ok(inner)
                    }
                    (t, p) => Err(syntax(
                        self.text,
                        p,
                        &format!("expected `)` to close the `(` here, found {}", describe(&t)),
                    )),
                }
            }
            t => Err(syntax(
                self.text,
                at,
                &format!("expected a number, a name or `(`, found {}", describe(&t)),
            )),
        }
    }
}
