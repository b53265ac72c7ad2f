//! Lua's `math` functions that C computes with the platform's maths library (`math.sin`,
//! `math.exp`, ...), replaced by the same functions over [`crate::math`], so that a script
//! computes the same numbers natively (glibc), in the browser (musl) and everywhere else.
//!
//! Each keeps Lua 5.4's behaviour: numbers and numeric strings are accepted, the result is
//! a float; `math.atan(y [, x])` and `math.log(x [, base])` take their optional second
//! argument as in the reference implementation. `math.sqrt`, `math.fmod`, `math.floor` and
//! the rest are exact (IEEE) and stay Lua's own. The `^` operator still calls C's `pow`
//! (the Lua core, not the library; `x^2` is `x*x`), see the Lua API documentation.

use mlua::{Lua, Table};

use crate::math;

type Unary = fn(f64) -> f64;

/// Replaces the transcendental functions of the sandbox's `math` table.
pub(crate) fn register(lua: &Lua) -> mlua::Result<()> {
    let table: Table = lua.globals().get("math")?;
    let unary: [(&str, Unary); 6] = [
        ("sin", math::sin),
        ("cos", math::cos),
        ("tan", math::tan),
        ("asin", math::asin),
        ("acos", math::acos),
        ("exp", math::exp),
    ];
    for (name, f) in unary {
        table.set(name, lua.create_function(move |_, x: f64| Ok(f(x)))?)?;
    }
    table.set(
        "atan",
        lua.create_function(|_, (y, x): (f64, Option<f64>)| Ok(math::atan2(y, x.unwrap_or(1.0))))?,
    )?;
    table.set(
        "log",
        lua.create_function(|_, (x, base): (f64, Option<f64>)| {
            Ok(match base {
                None => math::ln(x),
                Some(2.0) => math::log2(x),
                Some(10.0) => math::log10(x),
                Some(b) => math::ln(x) / math::ln(b),
            })
        })?,
    )?;
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use mlua::{Lua, LuaOptions, StdLib};

    fn lua() -> Lua {
        let lua = Lua::new_with(StdLib::MATH | StdLib::STRING, LuaOptions::default()).unwrap();
        super::register(&lua).unwrap();
        lua
    }

    #[test]
    fn results_are_the_engine_functions() {
        let lua = lua();
        let f = |src: &str| lua.load(src).eval::<f64>().unwrap().to_bits();
        assert_eq!(
            f("return math.sin(0.7)"),
            crate::math::sin(0.7f64).to_bits()
        );
        assert_eq!(f("return math.cos(3)"), crate::math::cos(3.0f64).to_bits());
        assert_eq!(
            f("return math.tan('0.25')"),
            crate::math::tan(0.25f64).to_bits()
        );
        assert_eq!(
            f("return math.asin(0.3)"),
            crate::math::asin(0.3f64).to_bits()
        );
        assert_eq!(
            f("return math.acos(-0.3)"),
            crate::math::acos(-0.3f64).to_bits()
        );
        assert_eq!(
            f("return math.exp(1.5)"),
            crate::math::exp(1.5f64).to_bits()
        );
        assert_eq!(
            f("return math.atan(2)"),
            crate::math::atan(2.0f64).to_bits()
        );
        assert_eq!(
            f("return math.atan(-1, -2)"),
            crate::math::atan2(-1.0f64, -2.0).to_bits()
        );
        assert_eq!(f("return math.log(5)"), crate::math::ln(5.0f64).to_bits());
        assert_eq!(f("return math.log(8, 2)"), 3.0f64.to_bits());
        assert_eq!(f("return math.log(1000, 10)"), 3.0f64.to_bits());
        let base3 = crate::math::ln(81.0f64) / crate::math::ln(3.0f64);
        assert_eq!(f("return math.log(81, 3)"), base3.to_bits());
        let kind: String = lua.load("return math.type(math.sin(0))").eval().unwrap();
        assert_eq!(kind, "float");
    }

    #[test]
    fn a_wrong_argument_is_a_lua_error() {
        let lua = lua();
        let err = lua
            .load("return math.sin('leaf')")
            .eval::<f64>()
            .unwrap_err();
        assert!(
            err.to_string().contains("sin") || err.to_string().contains("number"),
            "{err}"
        );
        assert!(lua.load("return math.sin()").eval::<f64>().is_err());
    }
}
