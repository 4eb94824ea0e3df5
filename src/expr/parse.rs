//! Lexer and recursive-descent parser of the grammar in the module docs. The depth of the
//! syntax tree is limited to [`MAX_DEPTH`] and the parser's own recursion to
//! [`MAX_RECURSION`], so that neither parsing nor the recursive evaluation, compilation,
//! printing and dropping of a tree can overflow the stack, whatever the input.
use super::{is_function, BinOp, ExprError, Node, FUNC1, FUNC2};

/// Deepest syntax tree accepted: operators, signs and calls nested in one another. The load
/// expressions of the committed cases are at most 6 deep; a sum of 200 terms is 200 deep.
pub const MAX_DEPTH: usize = 200;
/// Deepest recursion of the parser (`expr` and `unary` entries: parentheses, call arguments,
/// signs). A fully parenthesised print ([`super::Expr::to_freefem`]) of a tree of depth `d`
/// re-parses within `3d` of these (a sign inside its parentheses is the deepest: 3 per level).
const MAX_RECURSION: usize = 4 * MAX_DEPTH;

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
    /// current recursion depth of `expr` and `unary`
    recursion: usize,
}

/// A subtree and its depth (a leaf is 1 deep).
type Tree = (Node, usize);

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
    /// Enter `expr` or `unary`: refused beyond [`MAX_RECURSION`].
    fn enter(&mut self) -> Result<(), ExprError> {
        self.recursion += 1;
        if self.recursion > MAX_RECURSION {
            return Err(ExprError::TooDeep { column: self.column(), limit: MAX_DEPTH });
        }
        Ok(())
    }
    /// A new node over subtrees of depth `below`: refused beyond [`MAX_DEPTH`].
    fn node(&self, node: Node, below: usize) -> Result<Tree, ExprError> {
        if below >= MAX_DEPTH {
            return Err(ExprError::TooDeep { column: self.column(), limit: MAX_DEPTH });
        }
        Ok((node, below + 1))
    }
    fn expr(&mut self) -> Result<Tree, ExprError> {
        self.enter()?;
        let (mut lhs, mut depth) = self.term()?;
        loop {
            let op = if self.eat('+') {
                BinOp::Add
            } else if self.eat('-') {
                BinOp::Sub
            } else {
                self.recursion -= 1;
                return Ok((lhs, depth));
            };
            let (rhs, d) = self.term()?;
            (lhs, depth) = self.node(Node::Bin(op, Box::new(lhs), Box::new(rhs)), depth.max(d))?;
        }
    }
    fn term(&mut self) -> Result<Tree, ExprError> {
        let (mut lhs, mut depth) = self.unary()?;
        loop {
            let op = if self.eat('*') {
                BinOp::Mul
            } else if self.eat('/') {
                BinOp::Div
            } else {
                return Ok((lhs, depth));
            };
            let (rhs, d) = self.unary()?;
            (lhs, depth) = self.node(Node::Bin(op, Box::new(lhs), Box::new(rhs)), depth.max(d))?;
        }
    }
    fn unary(&mut self) -> Result<Tree, ExprError> {
        self.enter()?;
        let tree = if self.eat('-') {
            let (a, d) = self.unary()?;
            self.node(Node::Neg(Box::new(a)), d)?
        } else if self.eat('+') {
            self.unary()?
        } else {
            self.power()?
        };
        self.recursion -= 1;
        Ok(tree)
    }
    fn power(&mut self) -> Result<Tree, ExprError> {
        let (base, db) = self.primary()?;
        if self.eat('^') {
            let (exp, de) = self.unary()?;
            self.node(Node::Bin(BinOp::Pow, Box::new(base), Box::new(exp)), db.max(de))
        } else {
            Ok((base, db))
        }
    }
    fn primary(&mut self) -> Result<Tree, ExprError> {
        let column = self.column();
        match self.peek().clone() {
            Tok::Num(v) => {
                self.pos += 1;
                Ok((Node::Num(v), 1))
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
                    Ok((Node::Pi, 1))
                } else {
                    Ok((Node::Var(name), 1))
                }
            }
            _ => Err(self.unexpected("a number, identifier or '('")),
        }
    }
    fn call(&mut self, name: String, column: usize) -> Result<Tree, ExprError> {
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
        let below = args.iter().map(|a| a.1).max().unwrap_or(0);
        let mut it = args.into_iter().map(|a| Box::new(a.0));
        let node = match (f1, f2, it.next(), it.next()) {
            (Some(f), _, Some(a), None) => Node::Call1(f, a),
            (_, Some(f), Some(a), Some(b)) => Node::Call2(f, a, b),
            _ => return Err(ExprError::WrongArity { name, column, expected, found: 0 }),
        };
        self.node(node, below)
    }
}

// ---------------------------------------------------------------- Expr API

/// The syntax tree of `src`.
pub(super) fn parse(src: &str) -> Result<Node, ExprError> {
    let toks = lex(src)?;
    if toks.len() == 1 {
        return Err(ExprError::Empty);
    }
    let mut p = Parser { toks, pos: 0, recursion: 0 };
    let (root, _) = p.expr()?;
    if *p.peek() != Tok::End {
        return Err(p.unexpected("an operator or end of input"));
    }
    Ok(root)
}
