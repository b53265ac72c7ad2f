//! The compiled form of an expression: the stack machine's operations and the shapes kept
//! apart from it. [`super::compile`] makes it, [`super::eval`] runs it.

use super::BinOp;

/// One operation of the stack machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Op {
    Const(f64),
    Param(u16),
    Global(u16),
    Rand,
    Neg,
    Not,
    Bin(BinOp),
    /// `and`: if the top is false keep it and jump, else pop it.
    JumpIfFalse(u32),
    /// `or`: if the top is true keep it and jump, else pop it.
    JumpIfTrue(u32),
    F1(Fn1),
    F2(Fn2),
}

/// Functions of one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Fn1 {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sqrt,
    Exp,
    Log,
    Abs,
    Floor,
    Ceil,
}

/// Functions of two arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Fn2 {
    Atan2,
    Min,
    Max,
}

/// The deepest stack an expression may need.
pub(super) const MAX_DEPTH: usize = 32;

/// A compiled expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr(pub(super) Repr);

/// The forms of a compiled expression.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Repr {
    Const(f64),
    Param(u16),
    Global(u16),
    /// One binary operator on two loads (`l*r2`, `w+1`): no stack machine.
    Bin(BinOp, Op, Op),
    /// Bytecode for a stack machine.
    Code(Box<[Op]>),
}

impl Expr {
    /// The value of a constant expression.
    #[must_use]
    pub fn constant(&self) -> Option<f64> {
        match self.0 {
            Repr::Const(v) => Some(v),
            _ => None,
        }
    }

    /// Whether the expression draws random numbers.
    #[must_use]
    pub fn is_random(&self) -> bool {
        matches!(&self.0, Repr::Code(ops) if ops.contains(&Op::Rand))
    }
}
