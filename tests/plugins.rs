//! Plugins working together in one session, as the `pge` command runs them: L-systems
//! drawing with the default turtle, rewriting rules refusing to change other plugins' host
//! objects, and the engine's services out of the scripts' reach. (Each plugin's own tests
//! run it alone; a plugin depends on the engine only.)

use pge_engine::{Engine, Session, SessionOptions};

fn session() -> Session {
    let engine = Engine::builder()
        .plugin(pge_lsystem::LSystemPlugin)
        .plugin(pge_turtle::TurtlePlugin)
        .plugin(pge_extruder::ExtruderPlugin)
        .build()
        .expect("engine");
    engine.session(SessionOptions::default()).expect("session")
}

fn model_of(s: &Session, code: &str) -> pge_engine::Result<pge_engine::geometry::Model> {
    let v = s.eval_value(code)?;
    let mut a = s.algorithm_from(v)?;
    pge_engine::algorithm::run(&mut *a, &s.context(), &mut |_| {})
}

const PLANT: &str = r#"
    local l = pge.LSystem("plant")
    l:createInstance(function() return pge.turtle{ angle = 25.7, width = 0.2, sides = 5 } end)
    l:axiom("F")
    l:rule("F -> F[+F]F[-F]F")
    l:iterations(2)
    return l"#;

#[test]
fn an_lsystem_draws_with_its_turtle_and_the_mesh_is_sound() {
    let s = session();
    let m = model_of(&s, PLANT).expect("grows");
    m.validate().expect("valid");
    assert_eq!(m.stats.modules, 61);
    // 25 segments plus the root.
    assert_eq!(m.stats.nodes, 26);
    let mesh = &m.meshes[0];
    let n = mesh.positions.len() as u32;
    assert!(mesh.indices.iter().all(|i| *i < n));
    assert!(mesh.normals.iter().all(|v| (v.length() - 1.0).abs() < 1e-3));
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    let (lo, hi) = m.bounds().expect("not empty");
    assert!(hi.y - lo.y > 4.0, "the plant grows up: {lo} {hi}");
}

#[test]
fn the_same_seed_gives_the_same_bytes() {
    let a = model_of(&session(), PLANT).expect("grows");
    let b = model_of(&session(), PLANT).expect("grows");
    let meta = Default::default();
    assert_eq!(
        pge_engine::export::glb_bytes(&a, &meta).expect("glb"),
        pge_engine::export::glb_bytes(&b, &meta).expect("glb")
    );
}

#[test]
fn turtle_methods_and_open_lsystems() {
    let s = session();
    let y: f64 = s
        .eval(
            "local t = pge.turtle{} t:forward(2) t:turn(90) t:forward(1) t:push() t:pitch(90) \
             t:forward() t:pop() return t:position().y",
        )
        .expect("runs");
    assert!((y - 2.0).abs() < 1e-6);
    // An open L-system: the bud reads the turtle's height and stops above 3.
    let m = model_of(
        &s,
        r#"local l = pge.LSystem("open")
        l:axiom{ A{} }
        l:RRule("A", function()
            if this:position().y < 3 then return { F{}, A{} } end
            return {}
        end)
        l:iterations(10)
        return l"#,
    )
    .expect("grows");
    assert_eq!(m.stats.modules, 3);
    assert_eq!(m.stats.nodes, 4);
}

#[test]
fn a_turtle_is_read_only_during_rrules() {
    let s = session();
    let e = model_of(
        &s,
        "local l = pge.LSystem('t')\nl:axiom('A')\nl:RRule('A', function()\n  this:forward(1)\n  return 'B'\nend)\nl:iterations(1)\nreturn l",
    )
    .expect_err("read-only");
    let e = e.to_string();
    assert!(
        e.starts_with("eval:4: RRule 'A': turtle:forward is not allowed"),
        "{e}"
    );
}

#[test]
fn bad_options_and_commands_are_errors() {
    let s = session();
    let e = s
        .eval_value("return pge.turtle{ angel = 3 }")
        .expect_err("typo")
        .to_string();
    assert!(e.contains("unknown option 'angel'"), "{e}");
    let e = model_of(&s, "local l = pge.LSystem('t')\nl:axiom('F]')\nreturn l")
        .expect_err("pop")
        .to_string();
    assert!(e.contains("']' (pop) without a matching '['"), "{e}");
}

#[test]
fn rewriting_rules_may_not_change_the_extruder() {
    let s = session();
    let value = s
        .eval_value(
            "local obj = pge.LSystem('x')
             obj:axiom{ A{} }
             obj:iterations(1)
             obj:createInstance(function()
               local e = pge.Extruder()
               e:polygon(4, 1)
               return { e = e, model = function(self) return self.e:model() end }
             end)
             obj:RRule('A', function()
               local m = pge.MatrixManipulator()   -- a free matrix is fine
               m:advance(1)
               this.e:extrude(1)
               return { A{} }
             end)
             return obj",
        )
        .expect("runs");
    let mut algorithm = s.algorithm_from(value).expect("an algorithm");
    let err = pge_engine::algorithm::run(&mut *algorithm, &s.context(), &mut |_| {})
        .expect_err("extrude in an RRule")
        .to_string();
    assert!(
        err.contains("RRule 'A': extruder:extrude is not allowed"),
        "{err}"
    );
    assert!(err.starts_with("eval:12:"), "{err}");
}

/// The string and the model of a stochastic L-system drawn by the default turtle, after
/// `prelude` ran.
fn stochastic(prelude: &str) -> (String, u64) {
    let s = session();
    s.eval::<()>(prelude).expect("prelude runs");
    let code = "local l = pge.LSystem('t')
        l:axiom('A')
        l:rule('A -> F[+A]A', 1) l:rule('A -> F[-A]', 1)
        -- A rule function: the classic rules' draws now happen while Lua is involved.
        l:RRule('F', function() return nil end)
        l:iterations(5)
        return l";
    let v = s.eval_value(code).expect("runs");
    let mut a = s.algorithm_from(v).expect("an algorithm");
    let m = pge_engine::algorithm::run(&mut *a, &s.context(), &mut |_| {}).expect("grows");
    let glb = pge_engine::export::glb_bytes(&m, &Default::default()).expect("glb");
    (format!("{} {}", m.stats.modules, glb.len()), m.stats.nodes)
}

#[test]
fn scripts_cannot_replace_the_engine_services() {
    let plain = stochastic("");
    assert!(plain.1 > 1, "the default turtle drew the plant");
    // Redefining pge.turtle and pge.random changes what the script calls, not what the
    // L-system uses for its default instance and its random draws.
    let replaced = stochastic(
        "pge.turtle = function() error('not the engine') end
         pge.random = function() return 0 end",
    );
    assert_eq!(plain, replaced);
}
