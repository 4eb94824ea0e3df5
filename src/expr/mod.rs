//! A tiny arithmetic expression language shared by the Rust solver and the
//! generated FreeFEM include files.
//!
//! Case files (TOML) give loads and material laws as strings such as
//! `"2e3*sin(pi*s)*sin(8*omega0*t)"` or `"E/(2*(1+0.4))"`. The same AST is
//! evaluated in Rust ([`Expr::eval`], [`Compiled::eval`]) and written out as
//! FreeFEM source ([`Expr::to_freefem`]), so both codes see identical
//! formulas. Quantities are whatever the caller's variables mean; the solver
//! uses SI units throughout (arc length `s` in m, time `t` in s, ...).
//!
//! Grammar (lowest to highest precedence):
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary ('^' unary)?            // right-assoc, -2^2 = -4, 2^-1 = 0.5
//! primary := number | ident | ident '(' expr (',' expr)? ')' | '(' expr ')'
//! ```
//! Functions: `sin cos tan exp log sqrt abs sinh cosh tanh atan asin acos`
//! (one argument) and `pow atan2 min max` (two arguments). `pi` is built in. Numbers are
//! finite decimal literals: `nan` and `inf` are not numbers of the language (they would be
//! read as names). Trees are at most [`MAX_DEPTH`] deep.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use thiserror::Error;

mod compile;
mod parse;
#[cfg(test)]
mod tests;

pub use compile::Compiled;
pub use parse::MAX_DEPTH;

/// Errors from parsing, compiling or evaluating an expression. Columns are
/// 1-based character positions in the source string.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ExprError {
    /// The source contains no tokens.
    #[error("empty expression")]
    Empty,
    /// A character that cannot start any token.
    #[error("invalid character '{ch}' at column {column}")]
    InvalidCharacter { ch: char, column: usize },
    /// A malformed or non-finite numeric literal.
    #[error("invalid number '{text}' at column {column}")]
    InvalidNumber { text: String, column: usize },
    /// A token that does not fit the grammar at this point.
    #[error("unexpected {found} at column {column}, expected {expected}")]
    Unexpected { found: String, column: usize, expected: &'static str },
    /// `name(...)` where `name` is not a known function.
    #[error("unknown function '{name}' at column {column}")]
    UnknownFunction { name: String, column: usize },
    /// A known function called with the wrong number of arguments.
    #[error("function '{name}' at column {column} takes {expected} argument(s), got {found}")]
    WrongArity { name: String, column: usize, expected: usize, found: usize },
    /// A function name used without parentheses (e.g. `2*sin`).
    #[error("function '{name}' used as a variable at column {column}")]
    FunctionAsVariable { name: String, column: usize },
    /// A free variable with no value (eval) or no slot (compile).
    #[error("unknown variable '{name}'")]
    UnknownVariable { name: String },
    /// Operators, signs, calls or parentheses nested deeper than the parser accepts.
    #[error("expression nested more than {limit} levels deep at column {column}")]
    TooDeep { column: usize, limit: usize },
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `a+b`
    Add,
    /// `a-b`
    Sub,
    /// `a*b`
    Mul,
    /// `a/b`
    Div,
    /// `a^b`, written as `pow(a,b)` for FreeFEM.
    Pow,
}

/// Defines a function enum, its name table, `name()` and `apply()` from one list.
macro_rules! functions {
    ($(#[$doc:meta])* $ty:ident, $table:ident, ($($arg:ident),+), { $($var:ident = $name:literal => $body:expr,)+ }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $ty { $(#[doc = concat!("`", $name, "`")] $var),+ }
        const $table: &[(&str, $ty)] = &[$(($name, $ty::$var)),+];
        impl $ty {
            /// Source / FreeFEM name.
            pub fn name(self) -> &'static str { match self { $($ty::$var => $name),+ } }
            fn apply(self, $($arg: f64),+) -> f64 { match self { $($ty::$var => $body),+ } }
        }
    };
}

functions!(
    /// One-argument functions (same names in FreeFEM).
    Func1, FUNC1, (x), {
    Sin = "sin" => x.sin(), Cos = "cos" => x.cos(), Tan = "tan" => x.tan(),
    Exp = "exp" => x.exp(), Log = "log" => x.ln(), Sqrt = "sqrt" => x.sqrt(),
    Abs = "abs" => x.abs(), Sinh = "sinh" => x.sinh(), Cosh = "cosh" => x.cosh(),
    Tanh = "tanh" => x.tanh(), Atan = "atan" => x.atan(), Asin = "asin" => x.asin(),
    Acos = "acos" => x.acos(),
});

functions!(
    /// Two-argument functions (same names in FreeFEM).
    Func2, FUNC2, (a, b), {
    Pow = "pow" => a.powf(b), Atan2 = "atan2" => a.atan2(b),
    Min = "min" => a.min(b), Max = "max" => a.max(b),
});

fn is_function(name: &str) -> bool {
    FUNC1.iter().any(|(n, _)| *n == name) || FUNC2.iter().any(|(n, _)| *n == name)
}

fn binop(op: BinOp, a: f64, b: f64) -> f64 {
    match op {
        BinOp::Add => a + b,
        BinOp::Sub => a - b,
        BinOp::Mul => a * b,
        BinOp::Div => a / b,
        BinOp::Pow => a.powf(b),
    }
}

/// AST node.
#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    /// Finite numeric literal.
    Num(f64),
    /// The built-in constant π.
    Pi,
    /// Free variable.
    Var(String),
    /// Unary minus.
    Neg(Box<Node>),
    /// Binary operation.
    Bin(BinOp, Box<Node>, Box<Node>),
    /// One-argument function call.
    Call1(Func1, Box<Node>),
    /// Two-argument function call.
    Call2(Func2, Box<Node>, Box<Node>),
}

/// A parsed expression.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    /// Root of the syntax tree.
    pub root: Node,
}

impl Expr {
    /// Parses `src`. Errors name the 1-based column and what was expected.
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        Ok(Expr { root: parse::parse(src)? })
    }

    /// Free identifiers (excluding `pi` and function names).
    pub fn variables(&self) -> BTreeSet<String> {
        fn walk(n: &Node, out: &mut BTreeSet<String>) {
            match n {
                Node::Num(_) | Node::Pi => {}
                Node::Var(v) => {
                    out.insert(v.clone());
                }
                Node::Neg(a) | Node::Call1(_, a) => walk(a, out),
                Node::Bin(_, a, b) | Node::Call2(_, a, b) => {
                    walk(a, out);
                    walk(b, out);
                }
            }
        }
        let mut out = BTreeSet::new();
        walk(&self.root, &mut out);
        out
    }

    /// Evaluates with variable values from `vars`; an identifier for which
    /// `vars` returns `None` gives [`ExprError::UnknownVariable`]. NaN/inf
    /// results are returned as-is.
    pub fn eval(&self, vars: &dyn Fn(&str) -> Option<f64>) -> Result<f64, ExprError> {
        fn ev(n: &Node, vars: &dyn Fn(&str) -> Option<f64>) -> Result<f64, ExprError> {
            Ok(match n {
                Node::Num(v) => *v,
                Node::Pi => std::f64::consts::PI,
                Node::Var(name) => vars(name).ok_or_else(|| ExprError::UnknownVariable { name: name.clone() })?,
                Node::Neg(a) => -ev(a, vars)?,
                Node::Bin(op, a, b) => binop(*op, ev(a, vars)?, ev(b, vars)?),
                Node::Call1(f, a) => f.apply(ev(a, vars)?),
                Node::Call2(f, a, b) => f.apply(ev(a, vars)?, ev(b, vars)?),
            })
        }
        ev(&self.root, vars)
    }

    /// Writes fully parenthesised FreeFEM source. Identifiers go through
    /// `rename`; `pi` stays `pi`; `a^b` becomes `pow(a,b)`; literals are
    /// written with Rust's shortest round-trip `{:e}` format, which always
    /// contains an exponent so FreeFEM reads a `real` (never an `int`, so no
    /// integer division) equal to the same f64.
    pub fn to_freefem(&self, rename: &dyn Fn(&str) -> String) -> String {
        fn em(n: &Node, r: &dyn Fn(&str) -> String) -> String {
            match n {
                Node::Num(v) if *v < 0.0 => format!("({v:e})"),
                Node::Num(v) => format!("{v:e}"),
                Node::Pi => "pi".to_string(),
                Node::Var(name) => r(name),
                Node::Neg(a) => format!("(-{})", em(a, r)),
                Node::Bin(BinOp::Pow, a, b) => format!("pow({},{})", em(a, r), em(b, r)),
                Node::Bin(op, a, b) => {
                    let c = match op {
                        BinOp::Add => '+',
                        BinOp::Sub => '-',
                        BinOp::Mul => '*',
                        _ => '/',
                    };
                    format!("({}{c}{})", em(a, r), em(b, r))
                }
                Node::Call1(f, a) => format!("{}({})", f.name(), em(a, r)),
                Node::Call2(f, a, b) => format!("{}({},{})", f.name(), em(a, r), em(b, r)),
            }
        }
        em(&self.root, rename)
    }
}

impl std::str::FromStr for Expr {
    type Err = ExprError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Expr::parse(s)
    }
}

/// Fully parenthesised form that re-parses to an equivalent expression.
impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_freefem(&|s| s.to_string()))
    }
}

/// Parses `src` and evaluates it with identifiers taken from `constants`.
pub fn eval_const(src: &str, constants: &BTreeMap<String, f64>) -> Result<f64, ExprError> {
    Expr::parse(src)?.eval(&|name| constants.get(name).copied())
}
