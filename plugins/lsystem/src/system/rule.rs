//! Rules as added: parsed left sides, conditions and successors, before compilation.

use crate::classic::{ModuleAst, PatternAst};
use crate::expr::Ast;
use crate::symbol::{Sym, SymbolTable};

/// One symbol of a left side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct PatternItem {
    pub(super) sym: Sym,
    /// The number of formal parameters, when the pattern names them.
    pub(super) arity: Option<u16>,
}

/// A left side: `left < pred > right`.
#[derive(Clone, Debug)]
pub(super) struct Lhs {
    pub(super) left: Vec<PatternItem>,
    pub(super) pred: PatternItem,
    pub(super) right: Vec<PatternItem>,
}

/// What computes a rule's successor.
#[derive(Clone, Debug)]
pub(super) enum Kind {
    Classic {
        condition: Option<Ast>,
        successor: Vec<ModuleAst>,
        weight: Option<f64>,
    },
    External(u32),
}

/// A rule as added, kept so that the system can be compiled again after a change.
#[derive(Clone, Debug)]
pub(super) struct RuleDef {
    pub(super) text: String,
    pub(super) origin: u32,
    pub(super) lhs: Lhs,
    /// Formal names of the parameter-reading items, in matching order.
    pub(super) formals: Vec<String>,
    pub(super) kind: Kind,
    /// The normalised left side, grouping stochastic alternatives.
    pub(super) key: String,
}

/// The text with its runs of whitespace collapsed to one space.
pub(super) fn normalise(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Interns the patterns' symbols.
pub(super) fn pattern_items(
    patterns: &[PatternAst],
    symbols: &mut SymbolTable,
) -> Vec<PatternItem> {
    patterns
        .iter()
        .map(|p| PatternItem {
            sym: symbols.intern(&p.name),
            arity: p.formals.as_ref().map(|f| f.len() as u16),
        })
        .collect()
}
