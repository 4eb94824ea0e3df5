//! The compiled form of an expression: variables resolved to slots, constant subtrees folded.
use super::{binop, BinOp, Expr, ExprError, Func1, Func2, Node};

impl Expr {
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
}

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
