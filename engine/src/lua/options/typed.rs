//! The typed getters of [`Options`]: numbers within [`Bounds`], integers, booleans,
//! strings, choices, colours, vectors, ranges, functions and nested tables, each with the
//! wording of the [module docs](super).

use std::ops::RangeInclusive;

use glam::Vec3;
use mlua::{FromLua, Function, Value};

use super::{Bounds, Options};
use crate::geometry::Material;
use crate::lua::math::LuaVec3;

impl Options {
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
    use mlua::Table;

    use crate::lua::options::tests::{read, session};
    use crate::lua::{Bounds, Options};

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
}
