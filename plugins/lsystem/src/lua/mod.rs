//! The Lua layer: `pge.LSystem` and symbol constructors. The services other plugins use
//! (default interpretation, read-only checks during rewriting rules) are the engine's
//! ([`pge_engine::lua::services`]).

mod algorithm;
mod config;
mod derive;
mod host;
mod interpret;
mod object;
mod stream;
mod symbols;

use std::cell::RefCell;
use std::rc::Rc;

use mlua::{Lua, Table};
use pge_engine::Plugin;

use crate::SymbolTable;

pub use algorithm::LSystemAlgorithm;
pub use derive::{Derivation, derive_value};
pub use object::LuaLSystem;

/// What the L-systems of one session share: the symbol names and the count of L-system
/// objects. (The read-only phase and the default interpreters are engine services:
/// [`pge_engine::lua::services`].)
#[derive(Default)]
pub(crate) struct Shared {
    pub symbols: Rc<RefCell<SymbolTable>>,
    pub instances: u32,
    pub tags: Rc<RefCell<symbols::SymbolTags>>,
}

pub(crate) fn with_shared<R>(lua: &Lua, f: impl FnOnce(&mut Shared) -> R) -> R {
    if lua.app_data_ref::<Shared>().is_none() {
        lua.set_app_data(Shared::default());
    }
    match lua.app_data_mut::<Shared>() {
        Some(mut s) => f(&mut s),
        None => f(&mut Shared::default()),
    }
}

/// The symbol table shared by every L-system of the session.
pub(crate) fn session_symbols(lua: &Lua) -> Rc<RefCell<SymbolTable>> {
    with_shared(lua, |s| s.symbols.clone())
}

/// The `pge.LSystem` plugin: L-system objects, `pge.sym`, and symbol constructors for every
/// undefined global whose name starts with an uppercase ASCII letter (`A{}`, `Apex{age = 2}`).
#[derive(Clone, Copy, Debug, Default)]
pub struct LSystemPlugin;

impl Plugin for LSystemPlugin {
    fn name(&self) -> &str {
        "lsystem"
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        with_shared(lua, |_| ());
        pge.set("LSystem", lua.create_function(object::new_lsystem)?)?;
        symbols::register(lua, pge)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::{Engine, Location, RunContext, Session, SessionOptions};

    fn session(seed: u64) -> Session {
        let engine = Engine::builder()
            .plugin(LSystemPlugin)
            .build()
            .expect("engine");
        engine
            .session(SessionOptions {
                seed,
                ..SessionOptions::default()
            })
            .expect("session")
    }

    fn derive_in(s: &Session, code: &str, steps: Option<u32>) -> pge_engine::Result<Derivation> {
        let value = s.eval_value(code)?;
        let ctx = RunContext {
            steps,
            ..s.context()
        };
        derive_value(s.lua(), &value, &ctx, &Location::new("eval", 0))
    }

    fn text(code: &str) -> String {
        let d = derive_in(&session(1), code, None).expect("derives");
        let mut out = Vec::new();
        d.write_text(&mut out).expect("writes");
        String::from_utf8(out).expect("utf8").trim_end().to_string()
    }

    fn error(code: &str) -> String {
        derive_in(&session(1), code, None)
            .expect_err("fails")
            .to_string()
    }

    #[test]
    fn one_table_never_stands_for_two_symbols() {
        let t = text(
            r#"local l = pge.LSystem("t")
            local b = {1}
            l:axiom{ Floor(b), Roof(b) }
            l:iterations(0)
            return l"#,
        );
        assert_eq!(t, "Floor(1) Roof(1)");
    }

    #[test]
    fn constructors_tag_tables_and_refuse_other_values_at_the_calling_line() {
        // `A()` is an empty symbol; a constructed symbol may be changed before it is
        // returned; a symbol passed to a constructor is copied.
        let t = text(
            r#"local l = pge.LSystem("t")
            l:axiom{ A(), B{2} }
            l:RRule("A", function()
                local s = C{1}
                s.v = 2
                local e = E{}
                e[1] = 4
                return { s, e, D(s), A() }
            end)
            l:RRule("B", function(b) return B(b) end)
            l:iterations(1)
            return l"#,
        );
        assert_eq!(t, "C(1) E(4) D(1) A B(2)");
        let s = session(1);
        let name: String = s
            .eval("local s = Apex{age = 1} return s.name .. getmetatable(s).__name")
            .expect("runs");
        assert_eq!(name, "Apexsymbol Apex");
        let e = error(
            "local l = pge.LSystem('t')\nl:axiom{ A{} }\nl:RRule('A', function()\n  return B(5)\nend)\nl:iterations(1)\nreturn l",
        );
        assert_eq!(
            e,
            "eval:4: the parameters of symbol 'B' must be one table (B{...}), not number"
        );
        let e = error("return A('x')");
        assert_eq!(
            e,
            "eval:1: the parameters of symbol 'A' must be one table (A{...}), not string"
        );
    }

    /// Derives `code` in a session of an engine with `limits` applied to its builder.
    fn derive_limited(
        code: &str,
        limits: impl FnOnce(pge_engine::EngineBuilder) -> pge_engine::EngineBuilder,
    ) -> pge_engine::Error {
        let engine = limits(Engine::builder().plugin(LSystemPlugin))
            .build()
            .expect("engine");
        let s = engine.session(SessionOptions::default()).expect("session");
        derive_in(&s, code, None).expect_err("stops")
    }

    #[test]
    fn limits_hold_inside_rule_functions() {
        use pge_engine::Error;
        let endless = "local l = pge.LSystem('t')\nl:axiom('A(1) A(2)')\n\
                       l:RRule('A', function(a)\n  while true do end\nend)\n\
                       l:iterations(1)\nreturn l";
        let e = derive_limited(endless, |b| b.instruction_limit(Some(1_000_000)));
        assert!(
            matches!(&e, Error::InstructionLimit { location, .. } if location.line == Some(4)),
            "{e:?}"
        );
        assert!(e.to_string().starts_with("eval:4:"), "{e}");
        let e = derive_limited(endless, |b| {
            b.time_limit(Some(std::time::Duration::from_millis(200)))
        });
        assert!(
            matches!(&e, Error::TimeLimit { location } if location.line == Some(4)),
            "{e:?}"
        );
        // Memory: every call keeps a new symbol with a growing table.
        let e = derive_limited(
            "local l = pge.LSystem('t')\nl:axiom('A(1)')\n\
             l:RRule('A', function(a) return { A{a[1]}, B{ big = string.rep('x', 1 << 20) } } end)\n\
             l:iterations(40)\nl:maxModules(100000000)\nreturn l",
            |b| b.memory_limit_mib(16),
        );
        assert!(matches!(&e, Error::MemoryLimit { .. }), "{e:?}");
        // The module cap, on strings only rule functions make.
        let e = derive_limited(
            "local l = pge.LSystem('big')\nl:axiom{ A{1} }\n\
             l:RRule('A', function(a) return { A{a[1]}, A{a[1] + 1} } end)\n\
             l:maxModules(100)\nl:iterations(20)\nreturn l",
            |b| b,
        );
        assert!(
            matches!(&e, Error::ModuleLimit { step: 7, count, max: 100, .. } if *count > 100),
            "{e:?}"
        );
    }

    #[test]
    fn only_plain_arrays_of_numbers_are_stored_unboxed() {
        // A table with a hole, a named field or a non-number travels as the same Lua table:
        // the rule of the next step sees the very table, and JSON writes its fields.
        let s = session(1);
        let d = derive_in(
            &s,
            r#"local l = pge.LSystem("t")
            local holey = A{1, 2, 3}
            holey[2] = nil
            l:axiom{ A{1, 2.5}, holey, A{1, v = 2}, A{1, "x"}, A{} }
            l:RRule("A", function(a) return A(a) end)
            l:iterations(2)
            return l"#,
            None,
        )
        .expect("derives");
        let mut out = Vec::new();
        d.write_json(&mut out).expect("json");
        let json: serde_json::Value = serde_json::from_slice(&out).expect("valid json");
        assert_eq!(json[0]["params"], serde_json::json!([1, 2.5]));
        assert_eq!(json[1]["params"], serde_json::json!({"1": 1, "3": 3}));
        assert_eq!(json[2]["params"], serde_json::json!({"1": 1, "v": 2}));
        assert_eq!(json[3]["params"], serde_json::json!([1, "x"]));
        assert_eq!(d.module_text(0), "A(1,2.5)");
    }

    #[test]
    fn successor_strings_with_rand_or_globals_are_evaluated_each_time() {
        let t = text(
            r#"local l = pge.LSystem("t")
            l:axiom{ A{}, A{}, A{} }
            l:RRule("A", function() return "B(rand())" end)
            l:iterations(1)
            return l"#,
        );
        let values: Vec<&str> = t.split(' ').collect();
        assert_eq!(values.len(), 3, "{t}");
        assert_ne!(values[0], values[1], "{t}");
        assert_ne!(values[1], values[2], "{t}");
        let t = text(
            r#"local l = pge.LSystem("t")
            l:axiom{ A{} }
            l:set("k", 0)
            l:beforeStep(function() l:set("k", l:get("k") + 1) end)
            l:RRule("A", function() return "A B(k)" end)
            l:iterations(3)
            return l"#,
        );
        assert_eq!(t, "A B(3) B(2) B(1)");
    }

    #[test]
    fn rule_functions_refuse_conditions() {
        for kind in ["RRule", "IRule"] {
            let e = error(&format!(
                r#"local l = pge.LSystem("t")
                l:axiom("A(1)")
                l:{kind}("A(x) : x > 2", function(a) return {{}} end)
                return l"#
            ));
            assert!(e.contains("condition"), "{kind}: {e}");
        }
    }

    #[test]
    fn classic_rules_through_lua() {
        let t = text(
            r#"local l = pge.LSystem("t")
            l:axiom("F") l:rule("F -> F[+F]F") l:iterations(2)
            return l"#,
        );
        assert_eq!(t, "F [ + F ] F [ + F [ + F ] F ] F [ + F ] F");
    }

    #[test]
    fn rule_functions_fall_through_delete_and_branch() {
        let t = text(
            r#"local l = pge.LSystem("t")
            l:axiom{ A{1}, B{}, C{}, D{} }
            l:RRule("A", function(a) if a[1] > 5 then return B{} end end)
            l:RRule("A", function(a) return { A{a[1] + 1}, { X{} }, "F(2.5)" } end)
            l:RRule("B", function() return {} end)
            l:RRule("C", function() return nil end)
            l:iterations(1)
            return l"#,
        );
        assert_eq!(t, "A(2) [ X ] F(2.5) C D");
    }

    #[test]
    fn contexts_pass_tables_leftmost_first_and_named_params_survive() {
        let t = text(
            r#"local l = pge.LSystem("t")
            l:axiom{ A{v = 1}, B{2}, C{v = 3} }
            l:RRule("A < B > C", function(a, b, c) return B{a.v * 100 + b[1] * 10 + c.v} end)
            l:iterations(1)
            return l"#,
        );
        assert_eq!(t, "A B(123) C");
        let s = session(1);
        let d = derive_in(
            &s,
            r#"local l = pge.LSystem("t") l:axiom{ A{v = 1, 7} } l:iterations(0) return l"#,
            None,
        )
        .expect("derives");
        let mut out = Vec::new();
        d.write_json(&mut out).expect("json");
        let json: serde_json::Value = serde_json::from_slice(&out).expect("valid json");
        assert_eq!(json[0]["name"], "A");
        assert_eq!(json[0]["params"]["v"], 1);
        assert_eq!(d.module_text(0), "A(7)");
    }

    #[test]
    fn rrules_read_the_instance_left_by_interpretation() {
        let t = text(
            r#"local l = pge.LSystem("t")
            l:createInstance(function()
                return { n = 0, reset = function(self) self.n = 0 end }
            end)
            l:axiom{ A{}, A{}, A{} }
            l:IRule("B", function() this.n = this.n + 1 return true end)
            l:RRule("A", function() return B{ this.n } end)
            l:iterations(1)
            return l"#,
        );
        assert_eq!(t, "B(0) B(1) B(2)");
    }

    #[test]
    fn writes_during_rrules_are_errors_naming_the_rule() {
        let e = error(
            "local l = pge.LSystem('t')\nl:axiom{ A{} }\nl:createInstance(function() return {} end)\n\
             l:RRule('A', function()\n  this.x = 1\n  return A{}\nend)\nl:iterations(1)\nreturn l",
        );
        assert!(e.starts_with("eval:5:"), "{e}");
        assert!(e.contains("RRule 'A'"), "{e}");
        let e = error(
            "local l = pge.LSystem('t')\nl:axiom{ A{} }\n\
             l:RRule('A', function()\n  l:set('k', 2)\n  return A{}\nend)\nl:iterations(1)\nreturn l",
        );
        assert!(e.starts_with("eval:4:"), "{e}");
        assert!(e.contains("read-only"), "{e}");
    }

    #[test]
    fn bad_successors_and_rules_point_at_their_line() {
        let e = error(
            "local l = pge.LSystem('t')\nl:axiom('A')\nl:RRule('A', function() return 5 end)\nl:iterations(1)\nreturn l",
        );
        assert!(
            e.starts_with("eval:3: the successor returned by RRule 'A' is integer;"),
            "{e}"
        );
        let e = error(
            "local l = pge.LSystem('t')\nl:axiom('A')\nl:rule('A(x) -> B(y)')\nl:iterations(1)\nreturn l",
        );
        assert_eq!(e, "eval:3: rule 'A(x) -> B(y)': unknown name 'y'");
        let e = error("local l = pge.LSystem('t')\nl:rule('A(1 -> B')\nreturn l");
        assert!(e.starts_with("eval:2: rule 'A(1 -> B'"), "{e}");
    }

    #[test]
    fn max_modules_stops_the_run_fast() {
        let e = error(
            "local l = pge.LSystem('big')\nl:axiom('F')\nl:rule('F -> FF')\nl:iterations(40)\nreturn l",
        );
        assert_eq!(
            e,
            "eval:1: L-system 'big': step 24: the string reached 16777216 modules, more than \
             maxModules (10000000)"
        );
        let typed = derive_in(
            &session(1),
            "local l = pge.LSystem('big')\nl:axiom('F')\nl:rule('F -> FF')\nl:iterations(40)\nreturn l",
            None,
        )
        .expect_err("too many");
        assert!(
            matches!(
                typed,
                pge_engine::Error::ModuleLimit {
                    step: 24,
                    max: 10_000_000,
                    ..
                }
            ),
            "{typed:?}"
        );
        let e = error(
            "local l = pge.LSystem('big')\nl:axiom('F')\nl:rule('F -> FF')\nl:maxModules(100)\nl:iterations(40)\nreturn l",
        );
        assert!(e.contains("step 7: the string reached 128 modules"), "{e}");
    }

    #[test]
    fn a_streamed_last_step_writes_what_a_kept_one_does() {
        // Without Lua in its last step the step is streamed while written; a callback
        // (doing nothing) keeps it whole. Both must write the same string.
        let system = r#"local l = pge.LSystem("t")
            l:axiom("A(1,10)")
            l:rule("A(l,w) : l > 0.3 -> !(w)F(l)[&(45)A(l*0.6,w*0.7)]/(137.5)A(l*0.9,w*0.7)", 2)
            l:rule("A(l,w) -> F(l)[+B(l)]A(l*0.9,w)", 1)
            l:rule("B(l) -> F(l)[-B(l*0.5)]")
            l:iterations(6)"#;
        let streamed =
            derive_in(&session(3), &format!("{system} return l"), None).expect("derives");
        let kept = derive_in(
            &session(3),
            &format!("{system} l:afterStep(function() end) return l"),
            None,
        )
        .expect("derives");
        assert!(streamed.len() > 100);
        assert_eq!(streamed.len(), kept.len());
        assert_eq!(streamed.steps, kept.steps);
        for write in [Derivation::write_text, Derivation::write_json] {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            write(&streamed, &mut a).expect("writes");
            write(&kept, &mut b).expect("writes");
            assert_eq!(a, b);
        }
        assert_eq!(streamed.module_text(57), kept.module_text(57));
        // The cap of the last step still holds: the error comes from the derivation.
        let e = error(
            "local l = pge.LSystem('big')\nl:axiom('A(1)')\nl:rule('A(x) -> A(x)A(x)')\nl:maxModules(100)\nl:iterations(7)\nreturn l",
        );
        assert!(e.contains("step 7: the string reached 102 modules"), "{e}");
    }

    #[test]
    fn randomness_is_per_instance_and_repeats_per_seed() {
        let code = r#"local l = pge.LSystem("t")
            l:axiom("AAAAAAAAAA")
            l:RRule("A", function() if pge.random() < 0.5 then return "B" end end)
            l:rule("A -> C", 1) l:rule("A -> D", 1)
            l:iterations(1)
            return l"#;
        let run = |seed| {
            let d = derive_in(&session(seed), code, None).expect("derives");
            (0..d.len()).map(|i| d.module_text(i)).collect::<String>()
        };
        assert_eq!(run(1), run(1));
        assert_ne!(run(1), run(2));
        assert!(run(3).contains('B'));
    }

    #[test]
    fn callbacks_globals_and_the_steps_override() {
        let s = session(1);
        let d = derive_in(
            &s,
            r#"local l = pge.LSystem("t")
            l:set("k", 2)
            l:axiom("A(1)")
            l:rule("A(x) -> A(x * k)")
            l:beforeStep(function() l:set("k", l:get("k") + 1) end)
            l:afterStep(function() steps_taken = (steps_taken or 0) + 1 end)
            l:iterations(5)
            return l"#,
            Some(2),
        )
        .expect("derives");
        assert_eq!(d.steps, 2);
        // k is 3 during step 1 and 4 during step 2: classic expressions see each step's value.
        assert_eq!(d.module_text(0), "A(12)");
        let steps: i64 = s.eval("return steps_taken").expect("counted");
        assert_eq!(steps, 2);
    }

    #[test]
    fn a_script_value_becomes_an_algorithm() {
        let s = session(1);
        let v = s
            .eval_value("local l = pge.LSystem('t') l:axiom('F') l:rule('F -> FF') l:iterations(3) return l")
            .expect("runs");
        let mut a = s.algorithm_from(v).expect("algorithm");
        let m = pge_engine::algorithm::run(&mut *a, &s.context(), &mut |_| {}).expect("runs");
        assert_eq!(m.stats.modules, 8);
    }

    #[test]
    fn irules_fall_through_in_order_and_brackets_can_be_interpreted() {
        let s = session(1);
        derive_in(
            &s,
            r#"log = {}
            local l = pge.LSystem("t")
            l:createInstance(function() return {} end)
            l:axiom("A[B]A")
            l:IRule("A", function() log[#log + 1] = "first" return false end)
            l:IRule("A", function() log[#log + 1] = "second" return 1 end)
            l:IRule("A", function() log[#log + 1] = "never" return true end)
            l:IRule("[", function() log[#log + 1] = "push" return true end)
            l:IRule("]", function() log[#log + 1] = "pop" return true end)
            l:iterations(0)
            return l"#,
            None,
        )
        .expect("derives");
        let log: String = s.eval("return table.concat(log, ' ')").expect("log");
        assert_eq!(log, "first second push pop first second");
    }

    #[test]
    fn before_step_may_replace_this_and_pge_sym_builds_any_symbol() {
        let t = text(
            r#"local l = pge.LSystem("t")
            l:createInstance(function() return { k = 1 } end)
            l:beforeStep(function() return { k = 7 } end)
            l:axiom{ pge.sym("[", {}), A{}, pge.sym("]") }
            l:RRule("A", function() return pge.sym("Tip", { this.k }) end)
            l:IRule("Tip", function() return true end)
            l:iterations(1)
            return l"#,
        );
        assert_eq!(t, "[ Tip(7) ]");
    }

    #[test]
    fn the_global_table_is_writable_in_irules() {
        let s = session(1);
        derive_in(
            &s,
            r#"local l = pge.LSystem("t")
            l:set("seen", 0)
            l:axiom("AAA")
            l:IRule("A", function() l:set("seen", l:get("seen") + 1) return true end)
            l:iterations(0)
            L = l
            return l"#,
            None,
        )
        .expect("derives");
        let seen: f64 = s.eval("return L:get('seen')").expect("seen");
        assert_eq!(seen, 3.0);
    }

    #[test]
    fn irules_match_left_contexts_in_the_interpreted_string() {
        let s = session(1);
        derive_in(
            &s,
            r#"log = {}
            local l = pge.LSystem("t")
            l:createInstance(function() return {} end)
            l:ignore("+")
            l:axiom("A(1)+B[A(2)C]D(3)B")
            l:IRule("A < B", function(a, b) log[#log + 1] = "AB" .. a[1] return true end)
            l:IRule("D < B", function(d, b) log[#log + 1] = "DB" .. d[1] return true end)
            l:IRule("A < C", function(a, c) log[#log + 1] = "AC" .. a[1] return true end)
            l:IRule("B < D", function(b, d) log[#log + 1] = "BD" return true end)
            l:iterations(0)
            return l"#,
            None,
        )
        .expect("derives");
        let log: String = s.eval("return table.concat(log, ' ')").expect("log");
        assert_eq!(log, "AB1 AC2 BD DB3");
        let e = error("local l = pge.LSystem('t')\nl:IRule('A > B', function() end)\nreturn l");
        assert!(
            e.starts_with("eval:2: IRule 'A > B': an interpretation rule has no right context"),
            "{e}"
        );
    }
}
