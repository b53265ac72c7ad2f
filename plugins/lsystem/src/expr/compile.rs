//! Syntax trees to compact bytecode, with constant folding and the common shapes kept
//! apart from the stack machine.

use super::code::{Expr, Fn1, Fn2, MAX_DEPTH, Op, Repr};
use super::eval::run;
use super::{Ast, BinOp, ExprError, Operand, UnOp};

struct Compiler<'r> {
    ops: Vec<Op>,
    depth: usize,
    max: usize,
    resolve: &'r mut dyn FnMut(&str) -> Option<Operand>,
}

impl Compiler<'_> {
    fn push(&mut self, op: Op, delta: isize) {
        self.ops.push(op);
        self.depth = (self.depth as isize + delta) as usize;
        self.max = self.max.max(self.depth);
    }
    fn emit(&mut self, ast: &Ast) -> Result<(), ExprError> {
        match ast {
            Ast::Num(v) => self.push(Op::Const(*v), 1),
            Ast::Name(n) => match (self.resolve)(n) {
                Some(Operand::Param(i)) => self.push(Op::Param(i), 1),
                Some(Operand::Global(i)) => self.push(Op::Global(i), 1),
                Some(Operand::Const(v)) => self.push(Op::Const(v), 1),
                None if n == "pi" || n == "PI" => self.push(Op::Const(std::f64::consts::PI), 1),
                None => return Err(ExprError(format!("unknown name '{n}'"))),
            },
            Ast::Unary(op, a) => {
                self.emit(a)?;
                self.push(if *op == UnOp::Neg { Op::Neg } else { Op::Not }, 0);
            }
            Ast::Binary(op @ (BinOp::And | BinOp::Or), a, b) => {
                self.emit(a)?;
                let at = self.ops.len();
                self.push(Op::JumpIfFalse(0), -1);
                self.emit(b)?;
                let end = self.ops.len() as u32;
                self.ops[at] = if *op == BinOp::And {
                    Op::JumpIfFalse(end)
                } else {
                    Op::JumpIfTrue(end)
                };
            }
            Ast::Binary(op, a, b) => {
                self.emit(a)?;
                self.emit(b)?;
                self.push(Op::Bin(*op), -1);
            }
            Ast::Call(name, args) => {
                let f1 = match name.as_str() {
                    "sin" => Some(Fn1::Sin),
                    "cos" => Some(Fn1::Cos),
                    "tan" => Some(Fn1::Tan),
                    "asin" => Some(Fn1::Asin),
                    "acos" => Some(Fn1::Acos),
                    "atan" => Some(Fn1::Atan),
                    "sqrt" => Some(Fn1::Sqrt),
                    "exp" => Some(Fn1::Exp),
                    "log" => Some(Fn1::Log),
                    "abs" => Some(Fn1::Abs),
                    "floor" => Some(Fn1::Floor),
                    "ceil" => Some(Fn1::Ceil),
                    _ => None,
                };
                let f2 = match name.as_str() {
                    "atan2" => Some(Fn2::Atan2),
                    "min" => Some(Fn2::Min),
                    "max" => Some(Fn2::Max),
                    _ => None,
                };
                let arity = |n: usize| {
                    if args.len() == n {
                        Ok(())
                    } else {
                        Err(ExprError(format!(
                            "{name}() takes {n} argument{}, got {}",
                            if n == 1 { "" } else { "s" },
                            args.len()
                        )))
                    }
                };
                if let Some(f) = f1 {
                    arity(1)?;
                    self.emit(&args[0])?;
                    self.push(Op::F1(f), 0);
                } else if let Some(f) = f2 {
                    arity(2)?;
                    self.emit(&args[0])?;
                    self.emit(&args[1])?;
                    self.push(Op::F2(f), -1);
                } else if name == "rand" || name == "random" {
                    match args.len() {
                        0 => self.push(Op::Rand, 1),
                        2 => {
                            // a + rand() * (b - a)
                            self.emit(&args[0])?;
                            self.push(Op::Rand, 1);
                            self.emit(&args[1])?;
                            self.emit(&args[0])?;
                            self.push(Op::Bin(BinOp::Sub), -1);
                            self.push(Op::Bin(BinOp::Mul), -1);
                            self.push(Op::Bin(BinOp::Add), -1);
                        }
                        n => {
                            return Err(ExprError(format!(
                                "rand() takes 0 or 2 arguments, got {n}"
                            )));
                        }
                    }
                } else {
                    return Err(ExprError(format!("unknown function '{name}'")));
                }
            }
        }
        Ok(())
    }
}

impl Expr {
    /// Compiles `ast`, resolving names with `resolve` (`pi` is always known).
    pub fn compile(
        ast: &Ast,
        resolve: &mut dyn FnMut(&str) -> Option<Operand>,
    ) -> Result<Expr, ExprError> {
        let mut c = Compiler {
            ops: Vec::new(),
            depth: 0,
            max: 0,
            resolve,
        };
        c.emit(ast)?;
        if c.max > MAX_DEPTH {
            return Err(ExprError(format!(
                "expression nested too deeply: it needs more than the limit of {MAX_DEPTH} pending values"
            )));
        }
        Ok(Expr(match c.ops.as_slice() {
            [Op::Const(v)] => Repr::Const(*v),
            [Op::Param(i)] => Repr::Param(*i),
            [Op::Global(i)] => Repr::Global(*i),
            _ if !c
                .ops
                .iter()
                .any(|o| matches!(o, Op::Param(_) | Op::Global(_) | Op::Rand)) =>
            {
                Repr::Const(run(&c.ops, &[], &[], &mut || 0.0))
            }
            [
                a @ (Op::Const(_) | Op::Param(_) | Op::Global(_)),
                b @ (Op::Const(_) | Op::Param(_) | Op::Global(_)),
                Op::Bin(op),
            ] => Repr::Bin(*op, *a, *b),
            _ => Repr::Code(c.ops.into_boxed_slice()),
        }))
    }
}
