//! Expressions of the classic notation: parsed once, compiled to a compact bytecode and
//! evaluated on `f64`s without Lua.
//!
//! Grammar, loosest first: `or` (`||`), `and` (`&&`), `not` (`!`), comparisons
//! (`< <= > >= == ~= !=`), `+ -`, `* / %`, unary `-`, `^` (right associative), then numbers,
//! names, calls and parentheses. Truth is "not zero"; comparisons give 1 or 0. Angles are in
//! degrees.

use std::fmt;

/// A syntax tree, kept until names can be resolved (parameters, globals).
#[derive(Clone, Debug, PartialEq)]
pub enum Ast {
    /// A number.
    Num(f64),
    /// A name: a parameter, a global or `pi`.
    Name(String),
    /// A unary operator.
    Unary(UnOp, Box<Ast>),
    /// A binary operator.
    Binary(BinOp, Box<Ast>, Box<Ast>),
    /// A function call.
    Call(String, Vec<Ast>),
}

/// Unary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnOp {
    /// `-x`
    Neg,
    /// `not x`
    Not,
}

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `%` (Lua's floored modulo)
    Mod,
    /// `^`
    Pow,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `==`
    Eq,
    /// `~=` or `!=`
    Ne,
    /// `and` / `&&` (short-circuit)
    And,
    /// `or` / `||` (short-circuit)
    Or,
}

/// A syntax or name error in an expression.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExprError(pub String);

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Op(&'static str),
}

fn tokenize(src: &str) -> Result<Vec<Tok>, ExprError> {
    const OPS: [&str; 21] = [
        "<=", ">=", "==", "~=", "!=", "&&", "||", "+", "-", "*", "/", "%", "^", "<", ">", "(", ")",
        ",", "!", "=", "?",
    ];
    let bytes = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c.is_ascii_digit()
            || (c == b'.' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                let mut j = i + 1;
                if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                    j += 1;
                }
                if j < bytes.len() && bytes[j].is_ascii_digit() {
                    i = j;
                    while i < bytes.len() && bytes[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let text = &src[start..i];
            let v: f64 = text
                .parse()
                .map_err(|_| ExprError(format!("bad number '{text}'")))?;
            out.push(Tok::Num(v));
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            out.push(Tok::Name(src[start..i].to_string()));
        } else {
            let rest = &src[i..];
            match OPS.iter().find(|op| rest.starts_with(**op)) {
                Some(op) if *op != "=" && *op != "?" => {
                    out.push(Tok::Op(op));
                    i += op.len();
                }
                _ => {
                    let ch = rest.chars().next().unwrap_or('?');
                    return Err(ExprError(format!(
                        "unexpected '{ch}' in expression '{src}'"
                    )));
                }
            }
        }
    }
    Ok(out)
}

/// How deeply an expression may nest (parentheses, unary operators, calls, and chains of
/// binary operators): the parser, the compiler and dropping the tree recurse this deep.
pub const MAX_NESTING: usize = 100;

struct Parser<'a> {
    toks: Vec<Tok>,
    pos: usize,
    src: &'a str,
    /// How many nested calls of the parser are running.
    level: usize,
}

/// A syntax tree and its depth.
type Node = (Ast, usize);

fn unary_node(op: UnOp, (a, d): Node) -> Node {
    (Ast::Unary(op, Box::new(a)), d + 1)
}

fn binary_node(op: BinOp, (a, da): Node, (b, db): Node) -> Node {
    (Ast::Binary(op, Box::new(a), Box::new(b)), da.max(db) + 1)
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos)
    }
    fn eat_op(&mut self, op: &str) -> bool {
        if matches!(self.peek(), Some(Tok::Op(o)) if *o == op) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn eat_word(&mut self, w: &str) -> bool {
        if matches!(self.peek(), Some(Tok::Name(n)) if n == w) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn err(&self, what: &str) -> ExprError {
        ExprError(format!("{what} in expression '{}'", self.src.trim()))
    }
    fn too_deep(&self) -> ExprError {
        let src = self.src.trim();
        let shown: String = src.chars().take(40).collect();
        let more = if shown.len() < src.len() { "..." } else { "" };
        ExprError(format!(
            "expression nested deeper than the limit of {MAX_NESTING} levels in '{shown}{more}'"
        ))
    }
    /// Checks a node's depth against [`MAX_NESTING`].
    fn checked(&self, node: Node) -> Result<Node, ExprError> {
        if node.1 > MAX_NESTING {
            return Err(self.too_deep());
        }
        Ok(node)
    }
    /// Runs a nested parse, refusing to recurse past [`MAX_NESTING`].
    fn nested(&mut self, f: fn(&mut Self) -> Result<Node, ExprError>) -> Result<Node, ExprError> {
        if self.level >= MAX_NESTING {
            return Err(self.too_deep());
        }
        self.level += 1;
        let node = f(self);
        self.level -= 1;
        node
    }
    fn or(&mut self) -> Result<Node, ExprError> {
        let mut a = self.and()?;
        while self.eat_word("or") || self.eat_op("||") {
            let b = self.and()?;
            a = self.checked(binary_node(BinOp::Or, a, b))?;
        }
        Ok(a)
    }
    fn and(&mut self) -> Result<Node, ExprError> {
        let mut a = self.not()?;
        while self.eat_word("and") || self.eat_op("&&") {
            let b = self.not()?;
            a = self.checked(binary_node(BinOp::And, a, b))?;
        }
        Ok(a)
    }
    fn not(&mut self) -> Result<Node, ExprError> {
        if self.eat_word("not") || self.eat_op("!") {
            let a = self.nested(Self::not)?;
            return self.checked(unary_node(UnOp::Not, a));
        }
        self.cmp()
    }
    fn cmp(&mut self) -> Result<Node, ExprError> {
        let mut a = self.add()?;
        loop {
            let op = match self.peek() {
                Some(Tok::Op("<")) => BinOp::Lt,
                Some(Tok::Op("<=")) => BinOp::Le,
                Some(Tok::Op(">")) => BinOp::Gt,
                Some(Tok::Op(">=")) => BinOp::Ge,
                Some(Tok::Op("==")) => BinOp::Eq,
                Some(Tok::Op("~=" | "!=")) => BinOp::Ne,
                _ => return Ok(a),
            };
            self.pos += 1;
            let b = self.add()?;
            a = self.checked(binary_node(op, a, b))?;
        }
    }
    fn add(&mut self) -> Result<Node, ExprError> {
        let mut a = self.mul()?;
        loop {
            let op = match self.peek() {
                Some(Tok::Op("+")) => BinOp::Add,
                Some(Tok::Op("-")) => BinOp::Sub,
                _ => return Ok(a),
            };
            self.pos += 1;
            let b = self.mul()?;
            a = self.checked(binary_node(op, a, b))?;
        }
    }
    fn mul(&mut self) -> Result<Node, ExprError> {
        let mut a = self.unary()?;
        loop {
            let op = match self.peek() {
                Some(Tok::Op("*")) => BinOp::Mul,
                Some(Tok::Op("/")) => BinOp::Div,
                Some(Tok::Op("%")) => BinOp::Mod,
                _ => return Ok(a),
            };
            self.pos += 1;
            let b = self.unary()?;
            a = self.checked(binary_node(op, a, b))?;
        }
    }
    fn unary(&mut self) -> Result<Node, ExprError> {
        if self.eat_op("-") {
            let a = self.nested(Self::unary)?;
            return self.checked(unary_node(UnOp::Neg, a));
        }
        if self.eat_op("+") {
            return self.nested(Self::unary);
        }
        self.pow()
    }
    fn pow(&mut self) -> Result<Node, ExprError> {
        let base = self.primary()?;
        if self.eat_op("^") {
            // Right associative, and binds tighter than a unary minus on its left.
            let exponent = self.nested(Self::unary)?;
            return self.checked(binary_node(BinOp::Pow, base, exponent));
        }
        Ok(base)
    }
    fn primary(&mut self) -> Result<Node, ExprError> {
        match self.toks.get(self.pos).cloned() {
            Some(Tok::Num(v)) => {
                self.pos += 1;
                Ok((Ast::Num(v), 1))
            }
            Some(Tok::Name(n)) => {
                if matches!(n.as_str(), "and" | "or" | "not") {
                    return Err(self.err(&format!("unexpected '{n}'")));
                }
                self.pos += 1;
                if self.eat_op("(") {
                    let mut args = Vec::new();
                    let mut depth = 1;
                    if !self.eat_op(")") {
                        loop {
                            let (arg, d) = self.nested(Self::or)?;
                            args.push(arg);
                            depth = depth.max(d + 1);
                            if self.eat_op(")") {
                                break;
                            }
                            if !self.eat_op(",") {
                                return Err(self.err("expected ',' or ')'"));
                            }
                        }
                    }
                    self.checked((Ast::Call(n, args), depth))
                } else {
                    Ok((Ast::Name(n), 1))
                }
            }
            Some(Tok::Op("(")) => {
                self.pos += 1;
                let e = self.nested(Self::or)?;
                if !self.eat_op(")") {
                    return Err(self.err("missing ')'"));
                }
                Ok(e)
            }
            Some(Tok::Op(o)) => Err(self.err(&format!("unexpected '{o}'"))),
            None => Err(self.err("unexpected end")),
        }
    }
}

/// Parses one expression.
pub fn parse(src: &str) -> Result<Ast, ExprError> {
    let toks = tokenize(src)?;
    let mut p = Parser {
        toks,
        pos: 0,
        src,
        level: 0,
    };
    if p.toks.is_empty() {
        return Err(ExprError("empty expression".into()));
    }
    let (ast, _) = p.or()?;
    if p.pos != p.toks.len() {
        return Err(p.err("unexpected text after the end"));
    }
    Ok(ast)
}

/// What a name resolves to when an expression is compiled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Operand {
    /// The i-th parameter of the matched modules.
    Param(u16),
    /// The i-th global.
    Global(u16),
    /// A constant.
    Const(f64),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fn1 {
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

impl Fn1 {
    fn call(self, x: f64) -> f64 {
        match self {
            Fn1::Sin => x.to_radians().sin(),
            Fn1::Cos => x.to_radians().cos(),
            Fn1::Tan => x.to_radians().tan(),
            Fn1::Asin => x.asin().to_degrees(),
            Fn1::Acos => x.acos().to_degrees(),
            Fn1::Atan => x.atan().to_degrees(),
            Fn1::Sqrt => x.sqrt(),
            Fn1::Exp => x.exp(),
            Fn1::Log => x.ln(),
            Fn1::Abs => x.abs(),
            Fn1::Floor => x.floor(),
            Fn1::Ceil => x.ceil(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fn2 {
    Atan2,
    Min,
    Max,
}

impl Fn2 {
    fn call(self, a: f64, b: f64) -> f64 {
        match self {
            Fn2::Atan2 => a.atan2(b).to_degrees(),
            Fn2::Min => a.min(b),
            Fn2::Max => a.max(b),
        }
    }
}

/// The deepest stack an expression may need.
const MAX_DEPTH: usize = 32;

/// A compiled expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr(Repr);

#[derive(Clone, Debug, PartialEq)]
enum Repr {
    Const(f64),
    Param(u16),
    Global(u16),
    /// One binary operator on two loads (`l*r2`, `w+1`): no stack machine.
    Bin(BinOp, Op, Op),
    /// Bytecode for a stack machine.
    Code(Box<[Op]>),
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

fn binary(op: BinOp, a: f64, b: f64) -> f64 {
    let t = |c: bool| if c { 1.0 } else { 0.0 };
    match op {
        BinOp::Add => a + b,
        BinOp::Sub => a - b,
        BinOp::Mul => a * b,
        BinOp::Div => a / b,
        BinOp::Mod => a - (a / b).floor() * b,
        BinOp::Pow => a.powf(b),
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

    /// The value of a constant expression.
    #[must_use]
    pub fn constant(&self) -> Option<f64> {
        match self.0 {
            Repr::Const(v) => Some(v),
            _ => None,
        }
    }

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

    /// Whether the expression draws random numbers.
    #[must_use]
    pub fn is_random(&self) -> bool {
        matches!(&self.0, Repr::Code(ops) if ops.contains(&Op::Rand))
    }
}

fn run(ops: &[Op], params: &[f64], globals: &[f64], rand: &mut dyn FnMut() -> f64) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn eval_with(src: &str, params: &[(&str, f64)]) -> f64 {
        let ast = parse(src).expect("parses");
        let names: Vec<&str> = params.iter().map(|p| p.0).collect();
        let values: Vec<f64> = params.iter().map(|p| p.1).collect();
        let mut resolve = |n: &str| {
            names
                .iter()
                .position(|x| *x == n)
                .map(|i| Operand::Param(i as u16))
        };
        let e = Expr::compile(&ast, &mut resolve).expect("compiles");
        e.eval(&values, &[], &mut || 0.25)
    }

    fn eval(src: &str) -> f64 {
        eval_with(src, &[])
    }

    #[test]
    fn precedence_and_associativity_follow_lua() {
        assert_eq!(eval("1 + 2 * 3"), 7.0);
        assert_eq!(eval("(1 + 2) * 3"), 9.0);
        assert_eq!(eval("2 ^ 3 ^ 2"), 512.0);
        assert_eq!(eval("-2 ^ 2"), -4.0);
        assert_eq!(eval("10 - 4 - 3"), 3.0);
        assert_eq!(eval("-7 % 3"), 2.0);
        assert_eq!(eval("1.5e1 / .5"), 30.0);
    }

    #[test]
    fn logic_and_comparisons_give_numbers() {
        assert_eq!(eval("1 < 2"), 1.0);
        assert_eq!(eval("2 <= 1"), 0.0);
        assert_eq!(eval("3 == 3 and 4 ~= 5"), 1.0);
        assert_eq!(eval("0 or 7"), 7.0);
        assert_eq!(eval("0 and 7"), 0.0);
        assert_eq!(eval("not 0"), 1.0);
        assert_eq!(eval("!(1 > 0) || 1 != 1"), 0.0);
    }

    #[test]
    fn functions_use_degrees() {
        assert!((eval("sin(30)") - 0.5).abs() < 1e-12);
        assert!((eval("atan2(1, 1)") - 45.0).abs() < 1e-12);
        assert_eq!(eval("max(2, min(5, 3))"), 3.0);
        assert_eq!(eval("floor(2.7) + ceil(0.2)"), 3.0);
        assert!((eval("pi") - std::f64::consts::PI).abs() < 1e-15);
        assert_eq!(eval("rand()"), 0.25);
        assert_eq!(eval("rand(2, 6)"), 3.0);
    }

    #[test]
    fn parameters_are_read_by_position() {
        assert_eq!(eval_with("l * w + 1", &[("l", 2.0), ("w", 3.0)]), 7.0);
        let e =
            Expr::compile(&parse("l").expect("ok"), &mut |_| Some(Operand::Param(1))).expect("ok");
        assert_eq!(e.eval(&[5.0, 6.0], &[], &mut || 0.0), 6.0);
    }

    #[test]
    fn constants_are_folded() {
        let e = Expr::compile(&parse("2 * 3 + 1").expect("ok"), &mut |_| None).expect("ok");
        assert_eq!(e.constant(), Some(7.0));
        let e = Expr::compile(&parse("rand()").expect("ok"), &mut |_| None).expect("ok");
        assert!(e.is_random());
    }

    #[test]
    fn nesting_past_the_limit_is_an_error_not_a_stack_overflow() {
        let deep = |open: &str, mid: &str, close: &str, n: usize| {
            format!("{}{mid}{}", open.repeat(n), close.repeat(n))
        };
        for src in [
            deep("(", "1", ")", 10_000),
            deep("-", "1", "", 10_000),
            deep("not ", "1", "", 10_000),
            deep("sin(", "1", ")", 10_000),
            deep("", "1", " + 1", 10_000),
            deep("2 ^ ", "1", "", 10_000),
            deep("1 < ", "1", "", 10_000),
        ] {
            let e = parse(&src).expect_err("too deep");
            assert!(
                e.0.contains(&format!("the limit of {MAX_NESTING} levels")),
                "{}",
                e.0
            );
        }
        assert_eq!(eval(&deep("(", "1 + 1", ")", 50)), 2.0);
        let e = Expr::compile(
            &parse(&deep("1 + (", "1", ")", 40)).expect("parses"),
            &mut |_| None,
        )
        .expect_err("too many pending values");
        assert!(e.0.contains("the limit of 32 pending values"), "{}", e.0);
    }

    #[test]
    fn errors_name_the_problem() {
        let unknown = Expr::compile(&parse("x + 1").expect("ok"), &mut |_| None);
        assert_eq!(unknown.expect_err("unknown").0, "unknown name 'x'");
        assert!(parse("1 +").expect_err("bad").0.contains("unexpected end"));
        assert!(parse("(1").expect_err("bad").0.contains("missing ')'"));
        assert!(
            parse("1 $ 2")
                .expect_err("bad")
                .0
                .contains("unexpected '$'")
        );
        let f = Expr::compile(&parse("foo(1)").expect("ok"), &mut |_| None);
        assert_eq!(f.expect_err("unknown fn").0, "unknown function 'foo'");
        let a = Expr::compile(&parse("sin(1, 2)").expect("ok"), &mut |_| None);
        assert_eq!(a.expect_err("arity").0, "sin() takes 1 argument, got 2");
    }
}
