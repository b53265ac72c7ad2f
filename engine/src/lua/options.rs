//! The one reader of option tables: `pge.Forest{ minDistance = 3, leaves = {...} }` into
//! typed Rust values, with the same wording for every mistake in every plugin.
//!
//! A constructor wraps its argument in an [`Options`], asks for each option with a typed
//! getter, and calls [`Options::finish`] to refuse the keys it never asked for:
//!
//! ```
//! use pge_engine::lua::{Bounds, Options};
//! use pge_engine::{Engine, Plugin};
//!
//! struct Forest;
//! impl Plugin for Forest {
//!     fn register(&self, lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
//!         pge.set("Forest", lua.create_function(|lua, v: mlua::Value| {
//!             let o = Options::new(lua, v, "pge.Forest")?;
//!             let distance = o.number("minDistance", Bounds::Above(0.0))?.unwrap_or(2.0);
//!             let species = o.integer("species", 1..=64)?.unwrap_or(1);
//!             let layout = o.choice("layout", &["poisson", "grid"])?.unwrap_or("poisson");
//!             o.finish()?;
//!             Ok(format!("{distance} {species} {layout}"))
//!         })?)
//!     }
//! }
//!
//! let engine = Engine::builder().plugin(Forest).build().unwrap();
//! let session = engine.session(Default::default()).unwrap();
//! let s: String = session.eval("return pge.Forest{ minDistance = 3 }").unwrap();
//! assert_eq!(s, "3 1 poisson");
//! let e = session.eval::<String>("return pge.Forest{ minDistance = -3 }").unwrap_err();
//! assert_eq!(e.to_string(), "eval:1: pge.Forest: minDistance must be a number > 0, got -3");
//! let e = session.eval::<String>("return pge.Forest{ minDistanse = 3 }").unwrap_err();
//! assert_eq!(
//!     e.to_string(),
//!     "eval:1: pge.Forest: unknown option 'minDistanse': 'minDistanse' is not an option (known: minDistance, species, layout)"
//! );
//! ```
//!
//! # Wording
//! Every error is a script error at the calling line (`FILE:LINE: `), then the constructor:
//! - wrong type or range: `pge.Forest: minDistance must be a number > 0, got -3` (`got` is
//!   the number, the quoted string for choices and colours, or the type name);
//! - missing: `pge.shape.sphere: radius is required (a number > 0)`;
//! - unknown key: `pge.Forest: unknown option 'minDistanse': 'minDistanse' is not an option
//!   (known: minDistance, species)` (both phrasings plugins used before, so that messages
//!   users have seen still read the same);
//! - not a table: `pge.Forest takes a table of options, got number`.
//!
//! Nested tables ([`Options::table`]) name their options by path (`leaves.perTip`).
//! [`KeyStyle::Quoted`] writes the option in quotes (`'angle' must be ...`), as the turtle
//! always has.

mod typed;

use std::cell::{OnceCell, RefCell};
use std::fmt;

use mlua::{Lua, Table, Value};

use super::errors::script_error;

/// The numbers an option accepts; its `Display` is the wording errors use (`a number > 0`).
/// Every bound also refuses NaN and infinities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bounds {
    /// Any finite number: `a finite number`.
    Finite,
    /// Greater than the bound: `a number > 0`.
    Above(f64),
    /// At least the bound: `a number >= 0`.
    AtLeast(f64),
    /// Inclusive on both ends: `a number between 0 and 1`.
    Between(f64, f64),
    /// Exclusive below, inclusive above: `a number greater than 0 and at most 4`.
    AboveAtMost(f64, f64),
}

impl Bounds {
    /// Whether `x` is accepted.
    #[must_use]
    pub fn contains(&self, x: f64) -> bool {
        x.is_finite()
            && match *self {
                Bounds::Finite => true,
                Bounds::Above(lo) => x > lo,
                Bounds::AtLeast(lo) => x >= lo,
                Bounds::Between(lo, hi) => x >= lo && x <= hi,
                Bounds::AboveAtMost(lo, hi) => x > lo && x <= hi,
            }
    }
}

impl fmt::Display for Bounds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Bounds::Finite => write!(f, "a finite number"),
            Bounds::Above(lo) => write!(f, "a number > {lo}"),
            Bounds::AtLeast(lo) => write!(f, "a number >= {lo}"),
            Bounds::Between(lo, hi) => write!(f, "a number between {lo} and {hi}"),
            Bounds::AboveAtMost(lo, hi) => {
                write!(f, "a number greater than {lo} and at most {hi}")
            }
        }
    }
}

/// How options are written in error messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum KeyStyle {
    /// `radius must be a number > 0, got -1` (the default).
    #[default]
    Plain,
    /// `'radius' must be a number > 0, got -1`.
    Quoted,
}

/// The string-keyed entries of an option table, in `next` order, and whether it has other
/// keys too (positional values, or mistakes [`Options::finish`] reports).
struct Entries {
    named: Vec<(Box<[u8]>, Value)>,
    others: bool,
}

/// A script's option table being read into typed values; see the [module docs](self).
///
/// Getters return `Ok(None)` for an absent option (the caller picks the default) and a
/// located script error for a present option of the wrong type or out of range. Each key
/// asked for becomes a known option; [`Options::finish`] refuses the others. Options given
/// as `nil` (no table at all) read as all absent.
pub struct Options {
    lua: Lua,
    table: Option<Table>,
    /// The table's string-keyed entries, read in one pass at the first getter, which then
    /// finds its key among them in Rust: a key asked of the table would be a new Lua
    /// string, made under a protected call, for each of the tens of options a constructor
    /// asks for. `None` for a table with a metatable, whose keys are read through it.
    entries: OnceCell<Option<Entries>>,
    what: String,
    prefix: String,
    style: KeyStyle,
    positional: Vec<&'static str>,
    known: RefCell<Vec<String>>,
}

impl Options {
    /// The options of constructor `what` (`"pge.Forest"`, named in every error): a table, or
    /// nil for none. Anything else is an error.
    pub fn new(lua: &Lua, value: Value, what: &str) -> mlua::Result<Options> {
        match value {
            Value::Nil => Ok(Options::build(lua, None, what)),
            Value::Table(t) => Ok(Options::build(lua, Some(t), what)),
            other => Err(script_error(
                lua,
                format!("{what} takes a table of options, got {}", other.type_name()),
            )),
        }
    }

    /// The options of constructor `what`, which must be a table: nil is an error too.
    pub fn table_required(lua: &Lua, value: Value, what: &str) -> mlua::Result<Options> {
        match value {
            Value::Table(t) => Ok(Options::build(lua, Some(t), what)),
            other => Err(script_error(
                lua,
                format!("{what} takes a table of options, got {}", other.type_name()),
            )),
        }
    }

    /// The options of constructor `what` in a table.
    #[must_use]
    pub fn from_table(lua: &Lua, table: Table, what: &str) -> Options {
        Options::build(lua, Some(table), what)
    }

    fn build(lua: &Lua, table: Option<Table>, what: &str) -> Options {
        Options {
            lua: lua.clone(),
            table,
            entries: OnceCell::new(),
            what: what.to_string(),
            prefix: String::new(),
            style: KeyStyle::Plain,
            positional: Vec::new(),
            known: RefCell::new(Vec::new()),
        }
    }

    /// Writes option names in this style (see [`KeyStyle`]).
    #[must_use]
    pub fn style(mut self, style: KeyStyle) -> Options {
        self.style = style;
        self
    }

    /// Lets the options in `keys` also be given by position: `keys[0]` as `t[1]`, and so on
    /// (`pge.shape.sphere{ {0, 1, 0}, 2 }`). A named value wins over a positional one.
    #[must_use]
    pub fn positional(mut self, keys: &[&'static str]) -> Options {
        self.positional = keys.to_vec();
        self
    }

    /// The constructor named in errors.
    #[must_use]
    pub fn what(&self) -> &str {
        &self.what
    }

    /// The table, if one was given.
    #[must_use]
    pub fn table(&self) -> Option<&Table> {
        self.table.as_ref()
    }

    /// The Lua state.
    #[must_use]
    pub fn lua(&self) -> &Lua {
        &self.lua
    }

    /// How option `key` is written in errors: its path, in this reader's style.
    #[must_use]
    pub fn name(&self, key: &str) -> String {
        match self.style {
            KeyStyle::Plain => format!("{}{key}", self.prefix),
            KeyStyle::Quoted => format!("'{}{key}'", self.prefix),
        }
    }

    /// `WHAT: message` at the calling line.
    #[must_use]
    pub fn error(&self, message: impl fmt::Display) -> mlua::Error {
        script_error(&self.lua, format!("{}: {message}", self.what))
    }

    /// `WHAT: KEY text` at the calling line, for checks the getters do not make
    /// (`leaves.perTip must have min <= max, got {5, 2}`).
    #[must_use]
    pub fn problem(&self, key: &str, text: impl fmt::Display) -> mlua::Error {
        self.error(format!("{} {text}", self.name(key)))
    }

    /// `WHAT: KEY must be NEED, got GOT`, for a value of the right type that is out of range
    /// (`got` shows the value: `-3`, `"x"`).
    #[must_use]
    pub fn invalid(
        &self,
        key: &str,
        need: impl fmt::Display,
        got: impl fmt::Display,
    ) -> mlua::Error {
        self.problem(key, format!("must be {need}, got {got}"))
    }

    /// `WHAT: KEY must be NEED, got TYPE`, for a value of the wrong type.
    #[must_use]
    pub fn wrong_type(&self, key: &str, need: impl fmt::Display, got: &Value) -> mlua::Error {
        self.invalid(key, need, got.type_name())
    }

    /// `WHAT: KEY is required (NEED)`.
    #[must_use]
    pub fn missing(&self, key: &str, need: impl fmt::Display) -> mlua::Error {
        self.problem(key, format!("is required ({need})"))
    }

    /// The raw value of `key` (nil when absent), for functions, userdata and shapes the
    /// getters do not cover. It becomes a known option.
    pub fn value(&self, key: &str) -> mlua::Result<Value> {
        {
            let mut known = self.known.borrow_mut();
            if !known.iter().any(|k| k == key) {
                known.push(key.to_string());
            }
        }
        let Some(t) = &self.table else {
            return Ok(Value::Nil);
        };
        let v = match self.entries()? {
            Some(entries) => entries
                .named
                .iter()
                .find(|(name, _)| **name == *key.as_bytes())
                .map_or(Value::Nil, |(_, v)| v.clone()),
            None => t.get(key)?,
        };
        if v.is_nil()
            && let Some(i) = self.positional.iter().position(|k| *k == key)
        {
            return t.raw_get(i + 1);
        }
        Ok(v)
    }

    /// The table's string-keyed entries, read the first time they are asked for; `None`
    /// without a table, or for a table with a metatable.
    fn entries(&self) -> mlua::Result<Option<&Entries>> {
        if let Some(entries) = self.entries.get() {
            return Ok(entries.as_ref());
        }
        let entries = match &self.table {
            Some(t) if t.metatable().is_none() => {
                let mut entries = Entries {
                    named: Vec::new(),
                    others: false,
                };
                t.for_each::<Value, Value>(|key, value| {
                    match key {
                        Value::String(s) => {
                            entries.named.push((Box::from(&s.as_bytes()[..]), value))
                        }
                        _ => entries.others = true,
                    }
                    Ok(())
                })?;
                Some(entries)
            }
            _ => None,
        };
        Ok(self.entries.get_or_init(|| entries).as_ref())
    }

    /// Marks `keys` as known without reading them (another reader takes them).
    pub fn allow(&self, keys: &[&str]) {
        let mut known = self.known.borrow_mut();
        for key in keys {
            if !known.iter().any(|k| k == key) {
                known.push((*key).to_string());
            }
        }
    }

    /// The options of a nested table `t` given at `key` (for tables found with
    /// [`Options::value`]).
    #[must_use]
    pub fn child(&self, key: &str, t: Table) -> Options {
        Options {
            lua: self.lua.clone(),
            table: Some(t),
            entries: OnceCell::new(),
            what: self.what.clone(),
            prefix: format!("{}{key}.", self.prefix),
            style: self.style,
            positional: Vec::new(),
            known: RefCell::new(Vec::new()),
        }
    }

    /// Refuses every key that no getter asked for (and that [`Options::allow`] did not
    /// allow): `unknown option 'minDistanse': 'minDistanse' is not an option (known:
    /// minDistance, species)`. Positional
    /// values declared with [`Options::positional`] are known.
    pub fn finish(&self) -> mlua::Result<()> {
        let Some(t) = &self.table else {
            return Ok(());
        };
        match self.entries()? {
            // Only string keys, in the order `pairs` gives them.
            Some(entries) if !entries.others => entries
                .named
                .iter()
                .try_for_each(|(name, _)| self.check_name(name)),
            _ => t
                .pairs::<Value, Value>()
                .try_for_each(|pair| match pair?.0 {
                    Value::String(s) => self.check_name(&s.as_bytes()),
                    Value::Integer(i) if i >= 1 && (i as usize) <= self.positional.len() => Ok(()),
                    Value::Integer(i) => Err(self.unknown(&format!("[{i}]"))),
                    other => Err(self.unknown(&format!("[{}]", other.type_name()))),
                }),
        }
    }

    /// Refuses the string key `name` unless a getter asked for it.
    fn check_name(&self, name: &[u8]) -> mlua::Result<()> {
        if self.known.borrow().iter().any(|n| name == n.as_bytes()) {
            Ok(())
        } else {
            Err(self.unknown(&String::from_utf8_lossy(name)))
        }
    }

    /// `unknown option 'KEY'`, for a key no getter asked for.
    fn unknown(&self, key: &str) -> mlua::Error {
        let known = self.known.borrow();
        let key = format!("{}{key}", self.prefix);
        self.error(format!(
            "unknown option '{key}': '{key}' is not an option (known: {})",
            known.join(", ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Engine, Session, SessionOptions};

    pub(super) fn session() -> Session {
        Engine::builder()
            .build()
            .expect("engine")
            .session(SessionOptions::default())
            .expect("session")
    }

    /// Runs `code` with a global `read(t)` that reads `t` with `f` and returns its result.
    pub(super) fn read<T: mlua::IntoLua + 'static>(
        code: &str,
        f: impl Fn(&Options) -> mlua::Result<T> + 'static,
    ) -> Result<String, String> {
        let s = session();
        let g = s
            .lua()
            .create_function(move |lua, v: Value| {
                let o = Options::new(lua, v, "pge.Test")?;
                let r = f(&o)?;
                o.finish()?;
                Ok(r)
            })
            .expect("function");
        s.lua().globals().set("read", g).expect("global");
        s.eval::<Value>(code)
            .map(|v| match v {
                Value::String(s) => s.to_string_lossy(),
                other => format!("{other:?}"),
            })
            .map_err(|e| e.to_string())
    }
    #[test]
    fn bounds_describe_themselves() {
        assert_eq!(Bounds::Finite.to_string(), "a finite number");
        assert_eq!(Bounds::AtLeast(0.0).to_string(), "a number >= 0");
        assert_eq!(
            Bounds::AboveAtMost(0.0, 4.0).to_string(),
            "a number greater than 0 and at most 4"
        );
        assert!(!Bounds::Finite.contains(f64::INFINITY));
        assert!(Bounds::AboveAtMost(0.0, 4.0).contains(4.0));
        assert!(!Bounds::AboveAtMost(0.0, 4.0).contains(0.0));
    }
    #[test]
    fn nested_tables_name_their_options_by_path() {
        let f = |o: &Options| {
            let leaves = o.table_options("leaves")?;
            let size = match &leaves {
                Some(l) => {
                    let s = l.positive("size")?;
                    l.finish()?;
                    s
                }
                None => None,
            };
            Ok(format!("{size:?}"))
        };
        assert_eq!(
            read("return read{ leaves = { size = 2 } }", f),
            Ok("Some(2.0)".into())
        );
        assert_eq!(
            read("return read{ leaves = { size = -2 } }", f),
            Err("eval:1: pge.Test: leaves.size must be a number > 0, got -2".into())
        );
        assert_eq!(
            read("return read{ leaves = { sise = 2 } }", f),
            Err("eval:1: pge.Test: unknown option 'leaves.sise': 'leaves.sise' is not an option (known: size)".into())
        );
        assert_eq!(
            read("return read{ leaves = 3 }", f),
            Err("eval:1: pge.Test: leaves must be a table of options, got integer".into())
        );
        assert_eq!(
            read("return read{ leaf = {} }", f),
            Err(
                "eval:1: pge.Test: unknown option 'leaf': 'leaf' is not an option (known: leaves)"
                    .into()
            )
        );
    }

    #[test]
    fn a_table_with_a_metatable_is_read_through_it() {
        let f = |o: &Options| {
            let size = o.positive("size")?;
            let depth = o.positive("depth")?;
            Ok(format!("{size:?} {depth:?}"))
        };
        let inherits = "setmetatable(t, { __index = { size = 2 } })";
        assert_eq!(
            read(
                &format!("local t = {{ depth = 1 }}\n{inherits}\nreturn read(t)"),
                f
            ),
            Ok("Some(2.0) Some(1.0)".into())
        );
        // Its own keys are still checked, the inherited ones are not its keys.
        assert_eq!(
            read(&format!("local t = {{ dept = 1 }}\n{inherits}\nreturn read(t)"), f),
            Err("eval:3: pge.Test: unknown option 'dept': 'dept' is not an option (known: size, depth)".into())
        );
        assert_eq!(
            read("return read{ size = 3, depth = 1, [2] = 1 }", f),
            Err("eval:1: pge.Test: unknown option '[2]': '[2]' is not an option (known: size, depth)".into())
        );
    }

    #[test]
    fn quoted_style_and_typed_errors() {
        let s = session();
        let g = s
            .lua()
            .create_function(|lua, v: Value| {
                let o = Options::new(lua, v, "pge.turtle")?.style(KeyStyle::Quoted);
                let a = o.number("angle", Bounds::Finite)?;
                o.finish()?;
                Ok(a)
            })
            .expect("function");
        s.lua().globals().set("turtle", g).expect("global");
        let e = s
            .eval::<Value>("return turtle{ angle = 0/0 }")
            .expect_err("nan");
        assert_eq!(
            e.to_string(),
            "eval:1: pge.turtle: 'angle' must be a finite number, got NaN"
        );
        match e {
            crate::Error::Script {
                location, message, ..
            } => {
                assert_eq!(location, crate::Location::new("eval", 1));
                assert_eq!(
                    message,
                    "pge.turtle: 'angle' must be a finite number, got NaN"
                );
            }
            other => panic!("not a script error: {other:?}"),
        }
    }
}
