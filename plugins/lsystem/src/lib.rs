//! L-systems for PGE: a rewriting engine in plain Rust and its Lua layer.
//!
//! Strings of modules are stored flat ([`ModuleString`]: interned [`Sym`]s, unboxed `f64`
//! parameters), rules are compiled once ([`System::prepare`]) and a derivation step
//! ([`System::step`]) never allocates per module. Classic productions (ABOP / cpfg notation)
//! are evaluated by a small bytecode interpreter; rules written as Lua functions reach the
//! engine through the [`Host`] trait.
//!
//! ```
//! use pge_lsystem::{ModuleString, NativeHost, StepOptions, SymbolTable, System};
//! use rand_mt::Mt;
//!
//! let mut symbols = SymbolTable::new();
//! let mut system = System::new();
//! system.add_production("A(l) : l > 1 -> F(l) [ +(30) A(l/2) ] A(l/2)", None, 0, &mut symbols).unwrap();
//! system.prepare(&symbols).unwrap();
//! let mut string = system.parse_string("A(4)", &mut symbols, &mut || 0.0).unwrap();
//! let mut next = ModuleString::new();
//! let mut rng = Mt::new(1);
//! for step in 1..=3 {
//!     let opts = StepOptions { step, max_modules: 1_000, stream: false };
//!     system.step(&string, &mut next, &mut NativeHost { rng: &mut rng }, &opts).unwrap();
//!     std::mem::swap(&mut string, &mut next);
//! }
//! assert_eq!(string.len(), 16);
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
pub use system::{Host, NativeHost, StepOptions, System};
