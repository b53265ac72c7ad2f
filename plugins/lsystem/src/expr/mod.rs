//! Expressions of the classic notation: parsed once, compiled to a compact bytecode and
//! evaluated on `f64`s without Lua.
//!
//! Grammar, loosest first: `or` (`||`), `and` (`&&`), `not` (`!`), comparisons
//! (`< <= > >= == ~= !=`), `+ -`, `* / %`, unary `-`, `^` (right associative), then numbers,
//! names, calls and parentheses. Truth is "not zero"; comparisons give 1 or 0. Angles are in
//! degrees.

//!
//! `parse` reads text into an [`Ast`], `compile` turns an `Ast` into
//! an [`Expr`] (its bytecode and shapes in `code`) and `eval` evaluates it.

mod code;
mod compile;
mod eval;
mod parse;

use std::fmt;

pub use self::code::Expr;
pub(crate) use self::eval::Arg;
pub use self::parse::{MAX_NESTING, parse};
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
