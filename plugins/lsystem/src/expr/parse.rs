//! Text to syntax trees: the tokenizer and a recursive-descent parser.

use super::{Ast, BinOp, ExprError, UnOp};

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
