//! What an L-system object holds, and what its algorithm runs from a copy of: the axiom,
//! the compiled system, the rule functions and callbacks, where each rule was defined.

use mlua::{Function, Table};
use pge_engine::Location;

use crate::{Sym, System};

/// Where an axiom comes from.
#[derive(Clone, Debug)]
pub(crate) enum Axiom {
    /// Classic notation.
    Text(String),
    /// An array of symbols (nested arrays are branches).
    Lua(Table),
}

/// A rule function (RRule) with its left side.
#[derive(Clone, Debug)]
pub(crate) struct LuaRule {
    pub func: Function,
    pub text: std::rc::Rc<str>,
    /// Index into [`Config::locations`].
    pub origin: u32,
}

/// An interpretation rule (IRule).
#[derive(Clone, Debug)]
pub(crate) struct LuaIRule {
    pub sym: Sym,
    /// Left context, leftmost first (matched in the string interpreted so far).
    pub left: Vec<Sym>,
    pub func: Function,
}

/// Everything an L-system object holds; the algorithm gets a copy.
#[derive(Clone, Debug)]
pub(crate) struct Config {
    pub name: String,
    pub location: Location,
    pub axiom: Option<(Axiom, Location)>,
    pub iterations: u32,
    pub create: Option<Function>,
    pub before: Option<Function>,
    pub after: Option<Function>,
    pub globals: Table,
    pub system: System,
    pub rrules: Vec<LuaRule>,
    pub irules: Vec<LuaIRule>,
    /// Where each rule was defined (the `origin` of rule errors).
    pub locations: Vec<Location>,
    pub max_modules: Option<usize>,
    pub every_step: bool,
    /// The object's index in the session, seeding its generator.
    pub index: u32,
}
