//! The expression parser and compiler: any text parses or fails, any parse compiles or
//! fails, and evaluation never panics.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_lsystem::expr::{Expr, Operand, parse};

fuzz_target!(|text: &str| {
    let Ok(ast) = parse(text) else { return };
    let mut resolve = |name: &str| match name {
        "x" => Some(Operand::Param(0)),
        "y" => Some(Operand::Param(1)),
        "g" => Some(Operand::Global(0)),
        "k" => Some(Operand::Const(2.5)),
        _ => None,
    };
    let Ok(expr) = Expr::compile(&ast, &mut resolve) else {
        return;
    };
    let mut r = 0.0;
    let _ = expr.eval(&[1.5, -2.0], &[0.25], &mut || {
        r += 0.31;
        r % 1.0
    });
});
