//! Evaluation of compiled expressions on `f64`s.

use super::BinOp;
use super::code::{Expr, Fn1, Fn2, MAX_DEPTH, Op, Repr};
use pge_engine::math;

impl Fn1 {
    fn call(self, x: f64) -> f64 {
        match self {
            Fn1::Sin => math::sin(x.to_radians()),
            Fn1::Cos => math::cos(x.to_radians()),
            Fn1::Tan => math::tan(x.to_radians()),
            Fn1::Asin => math::asin(x).to_degrees(),
            Fn1::Acos => math::acos(x).to_degrees(),
            Fn1::Atan => math::atan(x).to_degrees(),
            Fn1::Sqrt => x.sqrt(),
            Fn1::Exp => math::exp(x),
            Fn1::Log => math::ln(x),
            Fn1::Abs => x.abs(),
            Fn1::Floor => x.floor(),
            Fn1::Ceil => x.ceil(),
        }
    }
}

impl Fn2 {
    fn call(self, a: f64, b: f64) -> f64 {
        match self {
            Fn2::Atan2 => math::atan2(a, b).to_degrees(),
            Fn2::Min => a.min(b),
            Fn2::Max => a.max(b),
        }
    }
}

/// The value of a load (`Const`, `Param` or `Global`; other operations are never loads).
#[inline]
fn load(op: Op, params: &[f64], globals: &[f64]) -> f64 {
    match op {
        Op::Const(v) => v,
        Op::Param(i) => params[i as usize],
        Op::Global(i) => globals[i as usize],
        _ => f64::NAN,
    }
}

fn truth(v: f64) -> bool {
    v != 0.0
}

#[inline]
pub(super) fn binary(op: BinOp, a: f64, b: f64) -> f64 {
    let t = |c: bool| if c { 1.0 } else { 0.0 };
    match op {
        BinOp::Add => a + b,
        BinOp::Sub => a - b,
        BinOp::Mul => a * b,
        BinOp::Div => a / b,
        BinOp::Mod => a - (a / b).floor() * b,
        BinOp::Pow => math::powf(a, b),
        BinOp::Lt => t(a < b),
        BinOp::Le => t(a <= b),
        BinOp::Gt => t(a > b),
        BinOp::Ge => t(a >= b),
        BinOp::Eq => t(a == b),
        BinOp::Ne => t(a != b),
        // Only reached when both sides were evaluated by constant folding.
        BinOp::And => {
            if truth(a) {
                b
            } else {
                a
            }
        }
        BinOp::Or => {
            if truth(a) {
                a
            } else {
                b
            }
        }
    }
}

impl Expr {
    /// Evaluates with the matched modules' parameters, the globals and a uniform [0,1) source.
    #[inline]
    pub fn eval(&self, params: &[f64], globals: &[f64], rand: &mut dyn FnMut() -> f64) -> f64 {
        match &self.0 {
            Repr::Const(v) => *v,
            Repr::Param(i) => params[*i as usize],
            Repr::Global(i) => globals[*i as usize],
            Repr::Bin(op, a, b) => {
                binary(*op, load(*a, params, globals), load(*b, params, globals))
            }
            Repr::Code(ops) => run(ops, params, globals, rand),
        }
    }
}

pub(super) fn run(
    ops: &[Op],
    params: &[f64],
    globals: &[f64],
    rand: &mut dyn FnMut() -> f64,
) -> f64 {
    let mut stack = [0.0f64; MAX_DEPTH + 1];
    let mut sp = 0usize;
    let mut pc = 0usize;
    while pc < ops.len() {
        match ops[pc] {
            Op::Const(v) => {
                stack[sp] = v;
                sp += 1;
            }
            Op::Param(i) => {
                stack[sp] = params[i as usize];
                sp += 1;
            }
            Op::Global(i) => {
                stack[sp] = globals[i as usize];
                sp += 1;
            }
            Op::Rand => {
                stack[sp] = rand();
                sp += 1;
            }
            Op::Neg => stack[sp - 1] = -stack[sp - 1],
            Op::Not => stack[sp - 1] = if truth(stack[sp - 1]) { 0.0 } else { 1.0 },
            Op::Bin(op) => {
                sp -= 1;
                stack[sp - 1] = binary(op, stack[sp - 1], stack[sp]);
            }
            Op::JumpIfFalse(to) => {
                if truth(stack[sp - 1]) {
                    sp -= 1;
                } else {
                    pc = to as usize;
                    continue;
                }
            }
            Op::JumpIfTrue(to) => {
                if truth(stack[sp - 1]) {
                    pc = to as usize;
                    continue;
                }
                sp -= 1;
            }
            Op::F1(f) => stack[sp - 1] = f.call(stack[sp - 1]),
            Op::F2(f) => {
                sp -= 1;
                stack[sp - 1] = f.call(stack[sp - 1], stack[sp]);
            }
        }
        pc += 1;
    }
    stack[0]
}

/// A compiled expression with the globals of one step bound to their values: the common
/// shapes of successor arguments (`l`, `a0`, `l*r2`, `w+1`) evaluate without the stack
/// machine, branching on one small enum. The values are those of [`Expr::eval`], bit for bit.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Arg<'e> {
    /// A constant (globals folded in).
    Const(f64),
    /// A parameter.
    Param(u16),
    /// `param op constant`.
    ParamConst(BinOp, u16, f64),
    /// `constant op param`.
    ConstParam(BinOp, f64, u16),
    /// `param op param`.
    ParamParam(BinOp, u16, u16),
    /// Anything else, evaluated by [`Expr::eval`].
    Code(&'e Expr),
}

impl Expr {
    /// This expression with `globals` bound to their current values.
    pub(crate) fn bind(&self, globals: &[f64]) -> Arg<'_> {
        let value = |op: &Op| match op {
            Op::Const(v) => Some(*v),
            Op::Global(i) => Some(globals[*i as usize]),
            _ => None,
        };
        match &self.0 {
            Repr::Const(v) => Arg::Const(*v),
            Repr::Param(i) => Arg::Param(*i),
            Repr::Global(i) => Arg::Const(globals[*i as usize]),
            Repr::Bin(op, a, b) => match (a, b, value(a), value(b)) {
                (_, _, Some(x), Some(y)) => Arg::Const(binary(*op, x, y)),
                (Op::Param(i), _, None, Some(y)) => Arg::ParamConst(*op, *i, y),
                (_, Op::Param(j), Some(x), None) => Arg::ConstParam(*op, x, *j),
                (Op::Param(i), Op::Param(j), None, None) => Arg::ParamParam(*op, *i, *j),
                _ => Arg::Code(self),
            },
            Repr::Code(_) => Arg::Code(self),
        }
    }
}

impl Arg<'_> {
    /// The value, as [`Expr::eval`] of the expression bound gives it with these `globals`.
    #[inline(always)]
    pub(crate) fn eval(
        &self,
        params: &[f64],
        globals: &[f64],
        rand: &mut dyn FnMut() -> f64,
    ) -> f64 {
        match *self {
            Arg::Const(v) => v,
            Arg::Param(i) => params[i as usize],
            Arg::ParamConst(op, i, c) => binary(op, params[i as usize], c),
            Arg::ConstParam(op, c, j) => binary(op, c, params[j as usize]),
            Arg::ParamParam(op, i, j) => binary(op, params[i as usize], params[j as usize]),
            Arg::Code(e) => e.eval(params, globals, rand),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Expr, Operand, parse};

    #[test]
    fn bound_expressions_give_the_values_of_the_bytecode() {
        let names = ["l", "w"];
        let globals = [0.7, 137.5];
        let mut resolve = |n: &str| match names.iter().position(|x| *x == n) {
            Some(i) => Some(Operand::Param(i as u16)),
            None => match n {
                "r" => Some(Operand::Global(0)),
                "d" => Some(Operand::Global(1)),
                _ => None,
            },
        };
        let cases = [
            "l",
            "w",
            "r",
            "d",
            "2",
            "l*r",
            "r*l",
            "l*w",
            "r*d",
            "l/3",
            "3-w",
            "l%r",
            "w^r",
            "l < w",
            "d + rand()",
            "l*r + 1",
            "pi",
            "-l",
        ];
        for text in cases {
            let e = Expr::compile(&parse(text).expect("parses"), &mut resolve).expect("compiles");
            let arg = e.bind(&globals);
            for params in [[1.5, -2.25], [0.0, 3.0], [-7.0, 0.1]] {
                let want = e.eval(&params, &globals, &mut || 0.375);
                let got = arg.eval(&params, &globals, &mut || 0.375);
                assert_eq!(want.to_bits(), got.to_bits(), "{text} with {params:?}");
            }
        }
    }
}
