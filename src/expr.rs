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
//! (one argument) and `pow atan2 min max` (two arguments). `pi` is built in.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use thiserror::Error;

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

// ---------------------------------------------------------------- lexer

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Op(char),
    End,
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("number {v}"),
        Tok::Ident(s) => format!("identifier '{s}'"),
        Tok::Op(c) => format!("'{c}'"),
        Tok::End => "end of input".to_string(),
    }
}

fn lex(src: &str) -> Result<Vec<(Tok, usize)>, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let skip = |mut i: usize, p: &dyn Fn(char) -> bool| {
        while chars.get(i).is_some_and(|&c| p(c)) {
            i += 1;
        }
        i
    };
    let digit = |c: char| c.is_ascii_digit();
    let word = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        let column = i + 1;
        let start = i;
        if c.is_whitespace() {
            i += 1;
        } else if digit(c) || (c == '.' && chars.get(i + 1).is_some_and(|&d| digit(d))) {
            i = skip(i, &digit);
            if chars.get(i) == Some(&'.') {
                i = skip(i + 1, &digit);
            }
            if matches!(chars.get(i), Some('e' | 'E')) {
                i += 1;
                if matches!(chars.get(i), Some('+' | '-')) {
                    i += 1;
                }
                // A malformed exponent swallows the rest of the word; parse() then fails.
                i = if chars.get(i).is_some_and(|&d| digit(d)) { skip(i, &digit) } else { skip(i, &word) };
            }
            let text: String = chars[start..i].iter().collect();
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => out.push((Tok::Num(v), column)),
                _ => return Err(ExprError::InvalidNumber { text, column }),
            }
        } else if c.is_ascii_alphabetic() || c == '_' {
            i = skip(i, &word);
            out.push((Tok::Ident(chars[start..i].iter().collect()), column));
        } else if "+-*/^(),".contains(c) {
            out.push((Tok::Op(c), column));
            i += 1;
        } else {
            return Err(ExprError::InvalidCharacter { ch: c, column });
        }
    }
    out.push((Tok::End, chars.len() + 1));
    Ok(out)
}

// ---------------------------------------------------------------- parser

struct Parser {
    toks: Vec<(Tok, usize)>,
    pos: usize,
}

impl Parser {
    fn peek(&self) -> &Tok {
        self.toks.get(self.pos).map_or(&Tok::End, |t| &t.0)
    }
    fn column(&self) -> usize {
        self.toks.get(self.pos).map_or(0, |t| t.1)
    }
    fn unexpected(&self, expected: &'static str) -> ExprError {
        ExprError::Unexpected { found: describe(self.peek()), column: self.column(), expected }
    }
    fn eat(&mut self, c: char) -> bool {
        if *self.peek() == Tok::Op(c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn expr(&mut self) -> Result<Node, ExprError> {
        let mut lhs = self.term()?;
        loop {
            let op = if self.eat('+') {
                BinOp::Add
            } else if self.eat('-') {
                BinOp::Sub
            } else {
                return Ok(lhs);
            };
            let rhs = self.term()?;
            lhs = Node::Bin(op, Box::new(lhs), Box::new(rhs));
        }
    }
    fn term(&mut self) -> Result<Node, ExprError> {
        let mut lhs = self.unary()?;
        loop {
            let op = if self.eat('*') {
                BinOp::Mul
            } else if self.eat('/') {
                BinOp::Div
            } else {
                return Ok(lhs);
            };
            let rhs = self.unary()?;
            lhs = Node::Bin(op, Box::new(lhs), Box::new(rhs));
        }
    }
    fn unary(&mut self) -> Result<Node, ExprError> {
        if self.eat('-') {
            Ok(Node::Neg(Box::new(self.unary()?)))
        } else if self.eat('+') {
            self.unary()
        } else {
            self.power()
        }
    }
    fn power(&mut self) -> Result<Node, ExprError> {
        let base = self.primary()?;
        if self.eat('^') {
            let exp = self.unary()?;
            Ok(Node::Bin(BinOp::Pow, Box::new(base), Box::new(exp)))
        } else {
            Ok(base)
        }
    }
    fn primary(&mut self) -> Result<Node, ExprError> {
        let column = self.column();
        match self.peek().clone() {
            Tok::Num(v) => {
                self.pos += 1;
                Ok(Node::Num(v))
            }
            Tok::Op('(') => {
                self.pos += 1;
                let e = self.expr()?;
                if !self.eat(')') {
                    return Err(self.unexpected("')'"));
                }
                Ok(e)
            }
            Tok::Ident(name) => {
                self.pos += 1;
                if self.eat('(') {
                    self.call(name, column)
                } else if is_function(&name) {
                    Err(ExprError::FunctionAsVariable { name, column })
                } else if name == "pi" {
                    Ok(Node::Pi)
                } else {
                    Ok(Node::Var(name))
                }
            }
            _ => Err(self.unexpected("a number, identifier or '('")),
        }
    }
    fn call(&mut self, name: String, column: usize) -> Result<Node, ExprError> {
        let f1 = FUNC1.iter().find(|(n, _)| *n == name).map(|x| x.1);
        let f2 = FUNC2.iter().find(|(n, _)| *n == name).map(|x| x.1);
        if f1.is_none() && f2.is_none() {
            return Err(ExprError::UnknownFunction { name, column });
        }
        let mut args = vec![self.expr()?];
        while self.eat(',') {
            args.push(self.expr()?);
        }
        if !self.eat(')') {
            return Err(self.unexpected("',' or ')'"));
        }
        let expected = if f1.is_some() { 1 } else { 2 };
        if args.len() != expected {
            return Err(ExprError::WrongArity { name, column, expected, found: args.len() });
        }
        let mut it = args.into_iter().map(Box::new);
        match (f1, f2, it.next(), it.next()) {
            (Some(f), _, Some(a), None) => Ok(Node::Call1(f, a)),
            (_, Some(f), Some(a), Some(b)) => Ok(Node::Call2(f, a, b)),
            _ => Err(ExprError::WrongArity { name, column, expected, found: 0 }),
        }
    }
}

// ---------------------------------------------------------------- Expr API

impl Expr {
    /// Parses `src`. Errors name the 1-based column and what was expected.
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        let toks = lex(src)?;
        if toks.len() == 1 {
            return Err(ExprError::Empty);
        }
        let mut p = Parser { toks, pos: 0 };
        let root = p.expr()?;
        if *p.peek() != Tok::End {
            return Err(p.unexpected("an operator or end of input"));
        }
        Ok(Expr { root })
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

    /// Resolves every variable to its index in `names` (the slot passed to
    /// [`Compiled::eval`]). Variable-free subtrees are folded to constants
    /// (with exactly the operations `eval` would perform).
    pub fn compile(&self, names: &[&str]) -> Result<Compiled, ExprError> {
        fn comp(n: &Node, names: &[&str]) -> Result<CNode, ExprError> {
            let c = match n {
                Node::Num(v) => CNode::Const(*v),
                Node::Pi => CNode::Const(std::f64::consts::PI),
                Node::Var(name) => match names.iter().position(|x| x == name) {
                    Some(i) => CNode::Slot(i),
                    None => return Err(ExprError::UnknownVariable { name: name.clone() }),
                },
                Node::Neg(a) => CNode::Neg(Box::new(comp(a, names)?)),
                Node::Bin(op, a, b) => CNode::Bin(*op, Box::new(comp(a, names)?), Box::new(comp(b, names)?)),
                Node::Call1(f, a) => CNode::F1(*f, Box::new(comp(a, names)?)),
                Node::Call2(f, a, b) => CNode::F2(*f, Box::new(comp(a, names)?), Box::new(comp(b, names)?)),
            };
            Ok(if c.is_const() { CNode::Const(c.eval(&[])) } else { c })
        }
        Ok(Compiled { root: comp(&self.root, names)?, n_slots: names.len() })
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

// ---------------------------------------------------------------- compiled form

#[derive(Debug, Clone, PartialEq)]
enum CNode {
    Const(f64),
    Slot(usize),
    Neg(Box<CNode>),
    Bin(BinOp, Box<CNode>, Box<CNode>),
    F1(Func1, Box<CNode>),
    F2(Func2, Box<CNode>, Box<CNode>),
}

impl CNode {
    fn is_const(&self) -> bool {
        match self {
            CNode::Const(_) => true,
            CNode::Slot(_) => false,
            CNode::Neg(a) | CNode::F1(_, a) => a.is_const(),
            CNode::Bin(_, a, b) | CNode::F2(_, a, b) => a.is_const() && b.is_const(),
        }
    }
    #[inline]
    fn eval(&self, s: &[f64]) -> f64 {
        match self {
            CNode::Const(v) => *v,
            CNode::Slot(i) => s.get(*i).copied().unwrap_or(f64::NAN),
            CNode::Neg(a) => -a.eval(s),
            CNode::Bin(op, a, b) => binop(*op, a.eval(s), b.eval(s)),
            CNode::F1(f, a) => f.apply(a.eval(s)),
            CNode::F2(f, a, b) => f.apply(a.eval(s), b.eval(s)),
        }
    }
}

/// An expression with identifiers resolved to slot indices (see [`Expr::compile`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Compiled {
    root: CNode,
    n_slots: usize,
}

impl Compiled {
    /// Evaluates with `slots[i]` the value of `names[i]` given to `compile`.
    /// No string lookups. A slot index beyond `slots.len()` reads as NaN
    /// (never panics); pass at least [`Compiled::n_slots`] values.
    #[inline]
    pub fn eval(&self, slots: &[f64]) -> f64 {
        self.root.eval(slots)
    }
    /// Number of names the expression was compiled against.
    pub fn n_slots(&self) -> usize {
        self.n_slots
    }
    /// The constant value if the expression has no variables.
    pub fn as_constant(&self) -> Option<f64> {
        match self.root {
            CNode::Const(v) => Some(v),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(src: &str) -> f64 {
        Expr::parse(src)
            .expect("parse")
            .eval(&|n| match n {
                "x" => Some(0.3),
                "y" => Some(-1.7),
                "s" => Some(0.25),
                "t" => Some(0.01),
                _ => None,
            })
            .expect("eval")
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(ev("1+2*3"), 7.0);
        assert_eq!(ev("(1+2)*3"), 9.0);
        assert_eq!(ev("8/4/2"), 1.0);
        assert_eq!(ev("8-4-2"), 2.0);
        assert_eq!(ev("2^3^2"), 512.0);
        assert_eq!(ev("2*3^2"), 18.0);
        assert_eq!(ev("-2^2"), -4.0);
        assert_eq!(ev("(-2)^2"), 4.0);
        assert_eq!(ev("2^-1"), 0.5);
        assert_eq!(ev("--3"), 3.0);
        assert_eq!(ev("+3 - -2"), 5.0);
        assert_eq!(ev("-x*y"), -0.3 * -1.7);
        assert_eq!(ev("1e-3 + .5 + 2. + 2E+1"), 1e-3 + 0.5 + 2.0 + 20.0);
        assert_eq!(ev("pi"), std::f64::consts::PI);
    }

    #[test]
    fn every_function() {
        let x: f64 = 0.3;
        let cases: [(&str, f64); 17] = [
            ("sin(x)", x.sin()),
            ("cos(x)", x.cos()),
            ("tan(x)", x.tan()),
            ("exp(x)", x.exp()),
            ("log(x)", x.ln()),
            ("sqrt(x)", x.sqrt()),
            ("abs(y)", 1.7),
            ("sinh(x)", x.sinh()),
            ("cosh(x)", x.cosh()),
            ("tanh(x)", x.tanh()),
            ("atan(x)", x.atan()),
            ("asin(x)", x.asin()),
            ("acos(x)", x.acos()),
            ("pow(x,y)", x.powf(-1.7)),
            ("atan2(y,x)", (-1.7f64).atan2(x)),
            ("min(x,y)", -1.7),
            ("max(x,y)", x),
        ];
        for (src, want) in cases {
            assert_eq!(ev(src), want, "{src}");
        }
        // Non-finite results are not errors.
        assert!(ev("log(y)").is_nan());
        assert_eq!(ev("1/0"), f64::INFINITY);
    }

    #[test]
    fn errors_with_positions() {
        let e = Expr::parse("(1+2))").unwrap_err();
        assert_eq!(e.to_string(), "unexpected ')' at column 6, expected an operator or end of input");
        let e = Expr::parse("sin(1+)").unwrap_err();
        assert!(matches!(e, ExprError::Unexpected { column: 7, .. }), "{e}");
        assert!(e.to_string().starts_with("unexpected ')' at column 7"));
        assert_eq!(
            Expr::parse("2*sinn(s)").unwrap_err(),
            ExprError::UnknownFunction { name: "sinn".into(), column: 3 }
        );
        assert_eq!(Expr::parse("2*sinn(s)").unwrap_err().to_string(), "unknown function 'sinn' at column 3");
        assert!(matches!(Expr::parse("pow(1)"), Err(ExprError::WrongArity { expected: 2, found: 1, .. })));
        assert!(matches!(Expr::parse("sin(1,2)"), Err(ExprError::WrongArity { expected: 1, found: 2, .. })));
        assert!(matches!(Expr::parse("1e"), Err(ExprError::InvalidNumber { column: 1, .. })));
        assert!(matches!(Expr::parse("1e999"), Err(ExprError::InvalidNumber { .. })));
        assert!(matches!(Expr::parse("  "), Err(ExprError::Empty)));
        assert!(matches!(Expr::parse("2 # 3"), Err(ExprError::InvalidCharacter { ch: '#', column: 3 })));
        assert!(matches!(Expr::parse("2*sin"), Err(ExprError::FunctionAsVariable { column: 3, .. })));
        assert!(matches!(Expr::parse("(1+2"), Err(ExprError::Unexpected { column: 5, .. })));
        assert!(matches!(Expr::parse("2 3"), Err(ExprError::Unexpected { column: 3, .. })));
        assert!(matches!(Expr::parse("*3"), Err(ExprError::Unexpected { column: 1, .. })));
        let e = Expr::parse("a+b").unwrap().eval(&|n| (n == "a").then_some(1.0)).unwrap_err();
        assert_eq!(e.to_string(), "unknown variable 'b'");
        assert_eq!(
            Expr::parse("a+b").unwrap().compile(&["a"]).unwrap_err(),
            ExprError::UnknownVariable { name: "b".into() }
        );
    }

    #[test]
    fn variables_and_constants() {
        let e = Expr::parse("-Fmax*(exp(4*s/L0)-1)/3 + pi*t").unwrap();
        let v: Vec<_> = e.variables().into_iter().collect();
        assert_eq!(v, ["Fmax", "L0", "s", "t"]);
        let mut c = BTreeMap::new();
        c.insert("E".to_string(), 1.1e5);
        assert_eq!(eval_const("E/(2*(1+0.4))", &c).unwrap(), 1.1e5 / (2.0 * (1.0 + 0.4)));
        assert!(matches!(eval_const("E/G", &c), Err(ExprError::UnknownVariable { .. })));
        assert_eq!(Expr::parse("2*pi").unwrap().compile(&[]).unwrap().as_constant(), Some(2.0 * std::f64::consts::PI));
    }

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
        fn unif(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
        fn pick(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    fn random_expr(r: &mut Rng, depth: u32) -> String {
        const VARS: [&str; 3] = ["a", "b", "c"];
        if depth == 0 || r.pick(4) == 0 {
            return match r.pick(3) {
                0 => format!("{}", (r.unif() * 10.0 * 1e3).round() / 1e3),
                1 => "pi".into(),
                _ => VARS[r.pick(3)].into(),
            };
        }
        let a = random_expr(r, depth - 1);
        let b = random_expr(r, depth - 1);
        match r.pick(8) {
            0 => format!("({a}+{b})"),
            1 => format!("{a}-{b}"),
            2 => format!("{a}*{b}"),
            3 => format!("({a})/({b})"),
            4 => format!("-{a}^2"),
            5 => format!("{}({a})", FUNC1[r.pick(FUNC1.len())].0),
            6 => format!("{}({a},{b})", FUNC2[r.pick(FUNC2.len())].0),
            _ => format!("({a})"),
        }
    }

    #[test]
    fn compile_matches_eval_and_display_roundtrip() {
        let mut r = Rng(0x9E3779B97F4A7C15);
        for _ in 0..500 {
            let src = random_expr(&mut r, 5);
            let e = Expr::parse(&src).unwrap_or_else(|err| panic!("{src}: {err}"));
            let c = e.compile(&["a", "b", "c"]).unwrap();
            let again = Expr::parse(&e.to_string()).unwrap();
            for _ in 0..5 {
                let vals = [r.unif() * 4.0 - 2.0, r.unif() * 4.0 - 2.0, r.unif()];
                let x = e
                    .eval(&|n| match n {
                        "a" => Some(vals[0]),
                        "b" => Some(vals[1]),
                        "c" => Some(vals[2]),
                        _ => None,
                    })
                    .unwrap();
                let y = c.eval(&vals);
                let z = again.compile(&["a", "b", "c"]).unwrap().eval(&vals);
                assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()), "{src}: {x} vs {y}");
                assert!(x.to_bits() == z.to_bits() || (x.is_nan() && z.is_nan()), "{src}: {x} vs {z}");
            }
        }
        // Too few slots: NaN instead of a panic.
        assert!(Expr::parse("a+b").unwrap().compile(&["a", "b"]).unwrap().eval(&[1.0]).is_nan());
    }

    #[test]
    fn number_format_roundtrip() {
        let vals = [
            0.1,
            1.0 / 3.0,
            2.07e2,
            207.0236,
            5e-324,
            f64::MAX,
            f64::MIN_POSITIVE,
            1.1e5 / 2.8,
            std::f64::consts::PI,
            0.30000000000000004,
            123456789012345680.0,
            2e3,
        ];
        for v in vals {
            let s = format!("{v:e}");
            assert!(s.contains('e'), "{s}");
            assert_eq!(s.parse::<f64>().unwrap(), v, "{s}");
            let e = Expr::parse(&s).unwrap();
            assert_eq!(e.eval(&|_| None).unwrap(), v);
        }
    }

    #[test]
    fn freefem_emitter() {
        let rename = |n: &str| match n {
            "s" => "S".to_string(),
            "t" => "T".to_string(),
            other => format!("k_{other}"),
        };
        let ff = |src: &str| Expr::parse(src).unwrap().to_freefem(&rename);
        assert_eq!(ff("2e3*sin(pi*s)*sin(8*omega0*t)"), "((2e3*sin((pi*S)))*sin(((8e0*k_omega0)*T)))");
        assert_eq!(ff("-F"), "(-k_F)");
        assert_eq!(ff("-Fmax*(exp(4*s/L0)-1)/3"), "(((-k_Fmax)*(exp(((4e0*S)/k_L0))-1e0))/3e0)");
        assert_eq!(ff("E/(2*(1+0.4))"), "(k_E/(2e0*(1e0+4e-1)))");
        assert_eq!(ff("-2^2 + atan2(s,t) + max(s, 1.5)"), "(((-pow(2e0,2e0))+atan2(S,T))+max(S,1.5e0))");
    }
}
