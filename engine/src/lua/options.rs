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

use std::cell::RefCell;
use std::fmt;
use std::ops::RangeInclusive;

use glam::Vec3;
use mlua::{FromLua, Function, Lua, Table, Value};

use super::errors::script_error;
use super::math::LuaVec3;
use crate::geometry::Material;

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

/// A script's option table being read into typed values; see the [module docs](self).
///
/// Getters return `Ok(None)` for an absent option (the caller picks the default) and a
/// located script error for a present option of the wrong type or out of range. Each key
/// asked for becomes a known option; [`Options::finish`] refuses the others. Options given
/// as `nil` (no table at all) read as all absent.
pub struct Options {
    lua: Lua,
    table: Option<Table>,
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
        let v: Value = t.get(key)?;
        if v.is_nil()
            && let Some(i) = self.positional.iter().position(|k| *k == key)
        {
            return t.raw_get(i + 1);
        }
        Ok(v)
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

    /// A number within `bounds`.
    pub fn number(&self, key: &str, bounds: Bounds) -> mlua::Result<Option<f64>> {
        let v = self.value(key)?;
        self.number_of(key, &v, bounds)
    }

    /// A number within `bounds` that also fits an `f32`.
    pub fn number_f32(&self, key: &str, bounds: Bounds) -> mlua::Result<Option<f32>> {
        let v = self.value(key)?;
        match self.number_of(key, &v, bounds)? {
            Some(x) if x.abs() > f64::from(f32::MAX) => Err(self.invalid(key, bounds, x)),
            x => Ok(x.map(|x| x as f32)),
        }
    }

    fn number_of(&self, key: &str, v: &Value, bounds: Bounds) -> mlua::Result<Option<f64>> {
        let x = match v {
            Value::Nil => return Ok(None),
            Value::Integer(i) => *i as f64,
            Value::Number(n) => *n,
            _ => return Err(self.wrong_type(key, bounds, v)),
        };
        if bounds.contains(x) {
            Ok(Some(x))
        } else {
            Err(self.invalid(key, bounds, shown(v)))
        }
    }

    /// A number > 0 that fits an `f32` (a length, a radius).
    pub fn positive(&self, key: &str) -> mlua::Result<Option<f32>> {
        self.number_f32(key, Bounds::Above(0.0))
    }

    /// A whole number in `range` (`2.0` is accepted, `2.5` is not).
    pub fn integer(&self, key: &str, range: RangeInclusive<i64>) -> mlua::Result<Option<i64>> {
        let v = self.value(key)?;
        self.integer_of(key, &v, &range)
    }

    fn integer_of(
        &self,
        key: &str,
        v: &Value,
        range: &RangeInclusive<i64>,
    ) -> mlua::Result<Option<i64>> {
        let need = || integer_need(range);
        let i = match v {
            Value::Nil => return Ok(None),
            Value::Integer(i) => *i,
            Value::Number(n) if n.fract() == 0.0 && n.abs() < 9.0e15 => *n as i64,
            Value::Number(n) => return Err(self.invalid(key, need(), n)),
            _ => return Err(self.wrong_type(key, need(), v)),
        };
        if range.contains(&i) {
            Ok(Some(i))
        } else {
            Err(self.invalid(key, need(), i))
        }
    }

    /// `true` or `false`.
    pub fn boolean(&self, key: &str) -> mlua::Result<Option<bool>> {
        match self.value(key)? {
            Value::Nil => Ok(None),
            Value::Boolean(b) => Ok(Some(b)),
            other => Err(self.wrong_type(key, "true or false", &other)),
        }
    }

    /// A string.
    pub fn string(&self, key: &str) -> mlua::Result<Option<String>> {
        match self.value(key)? {
            Value::Nil => Ok(None),
            Value::String(s) => Ok(Some(s.to_string_lossy())),
            other => Err(self.wrong_type(key, "a string", &other)),
        }
    }

    /// One of `choices`: `mode must be "fill", "surround" or "vertices", got "x"`.
    pub fn choice(
        &self,
        key: &str,
        choices: &[&'static str],
    ) -> mlua::Result<Option<&'static str>> {
        let v = self.value(key)?;
        if let Value::Nil = v {
            return Ok(None);
        }
        if let Value::String(s) = &v
            && let Some(c) = choices.iter().find(|c| s.as_bytes() == c.as_bytes())
        {
            return Ok(Some(c));
        }
        Err(match v {
            Value::String(_) => self.invalid(key, one_of(choices), shown(&v)),
            other => self.wrong_type(key, one_of(choices), &other),
        })
    }

    /// A colour `"#rrggbb"` (or `"#rrggbbaa"`), as linear RGBA.
    pub fn color(&self, key: &str) -> mlua::Result<Option<[f32; 4]>> {
        let v = self.value(key)?;
        self.color_of(key, &v)
    }

    fn color_of(&self, key: &str, v: &Value) -> mlua::Result<Option<[f32; 4]>> {
        match v {
            Value::Nil => Ok(None),
            Value::String(s) => Material::from_hex("", &s.to_string_lossy())
                .map(|m| Some(m.base_color))
                .map_err(|_| self.invalid(key, "a colour \"#rrggbb\"", shown(v))),
            other => Err(self.wrong_type(key, "a colour \"#rrggbb\"", other)),
        }
    }

    /// A vector: a `pge.vec3` or `{x, y, z}` (`{1, 2, 3}` or `{x = 1, y = 2, z = 3}`) of
    /// finite numbers.
    pub fn vec3(&self, key: &str) -> mlua::Result<Option<Vec3>> {
        let v = self.value(key)?;
        self.vec3_of(key, &v)
    }

    /// A vector as [`Options::vec3`] reads it, from a value found elsewhere (a list's items);
    /// `key` names it in errors (`roots[2]`).
    pub fn vec3_of(&self, key: &str, v: &Value) -> mlua::Result<Option<Vec3>> {
        const NEED: &str = "a vector {x, y, z}";
        match v {
            Value::Nil => Ok(None),
            Value::Table(_) | Value::UserData(_) => match LuaVec3::from_lua(v.clone(), &self.lua) {
                Ok(p) => Ok(Some(p.0)),
                Err(mlua::Error::FromLuaConversionError {
                    message: Some(why), ..
                }) => Err(self.problem(key, format!("must be {NEED}: {why}"))),
                Err(e) => Err(e),
            },
            other => Err(self.wrong_type(key, NEED, other)),
        }
    }

    /// A range `{min, max}` of numbers within `bounds` with `min <= max`, or one number `n`
    /// for `{n, n}`.
    pub fn range(&self, key: &str, bounds: Bounds) -> mlua::Result<Option<(f64, f64)>> {
        let v = self.value(key)?;
        let Value::Table(t) = &v else {
            return Ok(self.number_of(key, &v, bounds)?.map(|x| (x, x)));
        };
        let a = self.number_of(&format!("{key}[1]"), &t.raw_get(1)?, bounds)?;
        let b = self.number_of(&format!("{key}[2]"), &t.raw_get(2)?, bounds)?;
        let (Some(a), Some(b)) = (a, b) else {
            return Err(self.problem(key, format!("must be {{min, max}} of {bounds}")));
        };
        if a > b {
            return Err(self.problem(key, format!("must have min <= max, got {{{a}, {b}}}")));
        }
        Ok(Some((a, b)))
    }

    /// A range `{min, max}` of whole numbers in `range` with `min <= max`, or one whole
    /// number `n` for `{n, n}`.
    pub fn integer_range(
        &self,
        key: &str,
        range: RangeInclusive<i64>,
    ) -> mlua::Result<Option<(i64, i64)>> {
        let v = self.value(key)?;
        let Value::Table(t) = &v else {
            return Ok(self.integer_of(key, &v, &range)?.map(|x| (x, x)));
        };
        let a = self.integer_of(&format!("{key}[1]"), &t.raw_get(1)?, &range)?;
        let b = self.integer_of(&format!("{key}[2]"), &t.raw_get(2)?, &range)?;
        let (Some(a), Some(b)) = (a, b) else {
            return Err(self.problem(
                key,
                format!(
                    "must be {{min, max}} with {} <= min <= max <= {}",
                    range.start(),
                    range.end()
                ),
            ));
        };
        if a > b {
            return Err(self.problem(key, format!("must have min <= max, got {{{a}, {b}}}")));
        }
        Ok(Some((a, b)))
    }

    /// A function.
    pub fn function(&self, key: &str) -> mlua::Result<Option<Function>> {
        match self.value(key)? {
            Value::Nil => Ok(None),
            Value::Function(f) => Ok(Some(f)),
            other => Err(self.wrong_type(key, "a function", &other)),
        }
    }

    /// A nested table of options, read with the same wording; its options are named by
    /// path (`leaves.perTip`). Call [`Options::finish`] on it too.
    pub fn table_options(&self, key: &str) -> mlua::Result<Option<Options>> {
        match self.value(key)? {
            Value::Nil => Ok(None),
            Value::Table(t) => Ok(Some(self.child(key, t))),
            other => Err(self.wrong_type(key, "a table of options", &other)),
        }
    }

    /// The options of a nested table `t` given at `key` (for tables found with
    /// [`Options::value`]).
    #[must_use]
    pub fn child(&self, key: &str, t: Table) -> Options {
        Options {
            lua: self.lua.clone(),
            table: Some(t),
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
        let known = self.known.borrow();
        for pair in t.pairs::<Value, Value>() {
            let (k, _) = pair?;
            let ok = match &k {
                Value::String(s) => known.iter().any(|n| s.as_bytes() == n.as_bytes()),
                Value::Integer(i) => *i >= 1 && (*i as usize) <= self.positional.len(),
                _ => false,
            };
            if !ok {
                let key = match &k {
                    Value::String(s) => s.to_string_lossy(),
                    Value::Integer(i) => format!("[{i}]"),
                    other => format!("[{}]", other.type_name()),
                };
                let key = format!("{}{key}", self.prefix);
                return Err(self.error(format!(
                    "unknown option '{key}': '{key}' is not an option (known: {})",
                    known.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// A value as errors show what they got: numbers as written, strings quoted, other values
/// by type.
fn shown(v: &Value) -> String {
    match v {
        Value::Integer(i) => i.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("\"{}\"", s.to_string_lossy()),
        other => other.type_name().to_string(),
    }
}

fn integer_need(range: &RangeInclusive<i64>) -> String {
    if *range.end() == i64::MAX {
        format!("an integer >= {}", range.start())
    } else {
        format!("an integer between {} and {}", range.start(), range.end())
    }
}

/// `"a"`, `"a" or "b"`, `"a", "b" or "c"`.
fn one_of(choices: &[&str]) -> String {
    let quoted: Vec<String> = choices.iter().map(|c| format!("\"{c}\"")).collect();
    match quoted.split_last() {
        None => "nothing".into(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Engine, Session, SessionOptions};

    fn session() -> Session {
        Engine::builder()
            .build()
            .expect("engine")
            .session(SessionOptions::default())
            .expect("session")
    }

    /// Runs `code` with a global `read(t)` that reads `t` with `f` and returns its result.
    fn read<T: mlua::IntoLua + 'static>(
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
    fn numbers_in_bounds_and_their_errors() {
        let f = |o: &Options| {
            Ok(format!(
                "{:?} {:?}",
                o.number("a", Bounds::Between(0.0, 1.0))?,
                o.positive("b")?
            ))
        };
        assert_eq!(
            read("return read{ a = 0.5, b = 2 }", f),
            Ok("Some(0.5) Some(2.0)".into())
        );
        assert_eq!(read("return read{}", f), Ok("None None".into()));
        assert_eq!(read("return read()", f), Ok("None None".into()));
        assert_eq!(
            read("return read{ a = 2 }", f),
            Err("eval:1: pge.Test: a must be a number between 0 and 1, got 2".into())
        );
        assert_eq!(
            read("return read{ a = 'x' }", f),
            Err("eval:1: pge.Test: a must be a number between 0 and 1, got string".into())
        );
        assert_eq!(
            read("\nreturn read{ b = 0/0 }", f),
            Err("eval:2: pge.Test: b must be a number > 0, got NaN".into())
        );
        assert_eq!(
            read("return read{ b = 1e39 }", f),
            Err(format!(
                "eval:1: pge.Test: b must be a number > 0, got {}",
                1e39
            ))
        );
        assert_eq!(
            read("return read(3)", f),
            Err("eval:1: pge.Test takes a table of options, got integer".into())
        );
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
    fn integers_choices_strings_booleans_colours() {
        let f = |o: &Options| {
            Ok(format!(
                "{:?} {:?} {:?} {:?} {:?}",
                o.integer("n", 3..=64)?,
                o.choice("mode", &["fill", "surround", "vertices"])?,
                o.string("s")?,
                o.boolean("b")?,
                o.color("c")?,
            ))
        };
        assert_eq!(
            read(
                "return read{ n = 8.0, mode = 'fill', s = 'x', b = false, c = '#ffffff' }",
                f
            ),
            Ok("Some(8) Some(\"fill\") Some(\"x\") Some(false) Some([1.0, 1.0, 1.0, 1.0])".into())
        );
        let cases = [
            ("n = 2.5", "n must be an integer between 3 and 64, got 2.5"),
            ("n = 100", "n must be an integer between 3 and 64, got 100"),
            (
                "mode = 'x'",
                "mode must be \"fill\", \"surround\" or \"vertices\", got \"x\"",
            ),
            (
                "mode = 1",
                "mode must be \"fill\", \"surround\" or \"vertices\", got integer",
            ),
            ("s = {}", "s must be a string, got table"),
            ("b = 1", "b must be true or false, got integer"),
            ("c = 'red'", "c must be a colour \"#rrggbb\", got \"red\""),
        ];
        for (t, want) in cases {
            assert_eq!(
                read(&format!("return read{{ {t} }}"), f),
                Err(format!("eval:1: pge.Test: {want}")),
                "{t}"
            );
        }
        assert_eq!(
            read("return read{ n = -1 }", |o| Ok(format!(
                "{:?}",
                o.integer("n", 0..=i64::MAX)?
            ))),
            Err("eval:1: pge.Test: n must be an integer >= 0, got -1".into())
        );
    }

    #[test]
    fn vectors_ranges_and_positional_values() {
        let f = |o: &Options| {
            Ok(format!(
                "{:?} {:?} {:?}",
                o.vec3("at")?,
                o.range("scale", Bounds::Above(0.0))?,
                o.integer_range("count", 0..=1000)?
            ))
        };
        assert_eq!(
            read(
                "return read{ at = pge.vec3(1, 2, 3), scale = {0.5, 2}, count = 4 }",
                f
            ),
            Ok("Some(Vec3(1.0, 2.0, 3.0)) Some((0.5, 2.0)) Some((4, 4))".into())
        );
        assert_eq!(
            read("return read{ at = {x = 1, y = 0, z = 0}, scale = 1 }", f),
            Ok("Some(Vec3(1.0, 0.0, 0.0)) Some((1.0, 1.0)) None".into())
        );
        let cases = [
            ("at = 3", "at must be a vector {x, y, z}, got integer"),
            (
                "at = {1, 2}",
                "at must be a vector {x, y, z}: a vector table needs three numbers {x, y, z}",
            ),
            ("scale = {2, 1}", "scale must have min <= max, got {2, 1}"),
            ("scale = {0, 1}", "scale[1] must be a number > 0, got 0"),
            ("count = {5, 2}", "count must have min <= max, got {5, 2}"),
            (
                "count = {1, 2000}",
                "count[2] must be an integer between 0 and 1000, got 2000",
            ),
        ];
        for (t, want) in cases {
            assert_eq!(
                read(&format!("return read{{ {t} }}"), f),
                Err(format!("eval:1: pge.Test: {want}")),
                "{t}"
            );
        }
        let s = session();
        let h = s
            .lua()
            .create_function(|lua, t: Table| {
                let o = Options::from_table(lua, t, "pge.P").positional(&["center", "radius"]);
                let center = o.vec3("center")?;
                let r = o
                    .positive("radius")?
                    .ok_or_else(|| o.missing("radius", Bounds::Above(0.0)))?;
                o.finish()?;
                Ok(format!("{center:?} {r}"))
            })
            .expect("function");
        s.lua().globals().set("shape", h).expect("global");
        let v: String = s.eval("return shape{ {0, 1, 0}, 2 }").expect("positional");
        assert_eq!(v, "Some(Vec3(0.0, 1.0, 0.0)) 2");
        let v: String = s.eval("return shape{ radius = 3 }").expect("named");
        assert_eq!(v, "None 3");
        let e = s.eval::<String>("return shape{}").expect_err("missing");
        assert_eq!(
            e.to_string(),
            "eval:1: pge.P: radius is required (a number > 0)"
        );
        let e = s
            .eval::<String>("return shape{ {0, 1, 0}, 2, 3 }")
            .expect_err("extra");
        assert_eq!(
            e.to_string(),
            "eval:1: pge.P: unknown option '[3]': '[3]' is not an option (known: center, radius)"
        );
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
