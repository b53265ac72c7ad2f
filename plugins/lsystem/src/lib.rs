//! L-systems for PGE: a rewriting engine in plain Rust and its Lua layer.
//!
//! Strings of modules are stored flat ([`ModuleString`]: interned [`Sym`]s, unboxed `f64`
//! parameters), rules are compiled once ([`System::prepare`]) into a [`Prepared`] system,
//! whose one entry point ([`Prepared::derive`]) takes the steps the way the result allows
//! (kept, counted or handed out in pieces) and never allocates per module. Classic productions (ABOP / cpfg notation)
//! are evaluated by a small bytecode interpreter; rules written as Lua functions reach the
//! engine through the [`Host`] trait.
//!
//! ```
//! use pge_lsystem::{DeriveOptions, ModuleString, NativeHost, Output, SymbolTable, System};
//! use rand_mt::Mt;
//!
//! let mut symbols = SymbolTable::new();
//! let mut system = System::new();
//! system.add_production("A(l) : l > 1 -> F(l) [ +(30) A(l/2) ] A(l/2)", None, 0, &mut symbols).unwrap();
//! let prepared = system.prepare(&symbols).unwrap();
//! let axiom = system.parse_string("A(4)", &mut symbols, &mut || 0.0).unwrap();
//! let opts = DeriveOptions::new(1, 3, 1_000);
//! let mut rng = Mt::new(1);
//! let mut string = ModuleString::new();
//! prepared.derive(&axiom, &opts, &mut NativeHost { rng: &mut rng }, Output::Keep(&mut string)).unwrap();
//! assert_eq!(string.len(), 16);
//! // Counted without keeping the string of any step.
//! let mut rng = Mt::new(1);
//! let count = prepared.derive(&axiom, &opts, &mut NativeHost { rng: &mut rng }, Output::Count);
//! assert_eq!(count, Ok(16));
//! ```

mod classic;
mod error;
pub mod expr;
#[cfg(feature = "lua")]
mod lua;
mod module_string;
mod symbol;
mod system;

pub use error::LsError;
#[cfg(feature = "lua")]
pub use lua::{Derivation, LSystemAlgorithm, LSystemPlugin, LuaLSystem, derive_value};
pub use module_string::ModuleString;
pub use symbol::{Sym, SymbolTable};
pub use system::{DeriveOptions, Host, NativeHost, Output, Prepared, System};
