//! `pge.turtle{...}`: the turtle as a Lua object and as the L-systems' default interpretation.

use glam::Mat4;
use mlua::{AnyUserData, Lua, Table, UserData, UserDataMethods, Value};
use pge_engine::geometry::{Material, Model};
use pge_engine::lua::{LuaModel, LuaVec3, run_context, script_error};
use pge_lsystem::check_mutable;
use pge_tree::{LeafOptions, MeshOptions, RadiiMode, TreeOptions, build_tree};

use crate::turtle::{Turtle, TurtleError, TurtleOptions};

/// A turtle in Lua, with the options its model is meshed with.
pub struct LuaTurtle {
    /// The turtle.
    pub turtle: Turtle,
    mesh: MeshOptions,
    leaves: Option<LeafOptions>,
    palette: Vec<[f32; 4]>,
}

const KEYS: &[&str] = &[
    "angle",
    "step",
    "width",
    "widthFactor",
    "tropism",
    "elasticity",
    "sides",
    "leaves",
    "leafSize",
    "mesh",
    "colors",
];

fn number(lua: &Lua, t: &Table, key: &str, min: f64) -> mlua::Result<Option<f32>> {
    match t.get::<Value>(key)? {
        Value::Nil => Ok(None),
        Value::Integer(i) if i as f64 >= min => Ok(Some(i as f32)),
        Value::Number(n) if n.is_finite() && n >= min => Ok(Some(n as f32)),
        other => Err(script_error(
            lua,
            format!(
                "pge.turtle: '{key}' must be a finite number{}, got {}",
                if min > f64::MIN {
                    format!(" of at least {min}")
                } else {
                    String::new()
                },
                match other {
                    Value::Integer(i) => i.to_string(),
                    Value::Number(n) => n.to_string(),
                    o => o.type_name().to_string(),
                }
            ),
        )),
    }
}

fn options_error(lua: &Lua, e: impl std::fmt::Display) -> mlua::Error {
    script_error(lua, format!("pge.turtle: {e}"))
}

impl LuaTurtle {
    /// Reads `pge.turtle{...}` options.
    pub fn from_lua(lua: &Lua, t: Option<Table>) -> mlua::Result<LuaTurtle> {
        let mut o = TurtleOptions::default();
        let mut mesh = MeshOptions {
            radii: RadiiMode::Keep,
            ..MeshOptions::default()
        };
        let mut leaves = None;
        let mut palette = Vec::new();
        if let Some(t) = t {
            for pair in t.pairs::<Value, Value>() {
                let (k, _) = pair?;
                let key = k.to_string().unwrap_or_default();
                if !KEYS.contains(&key.as_str()) {
                    return Err(options_error(
                        lua,
                        format!("unknown option '{key}' (known: {})", KEYS.join(", ")),
                    ));
                }
            }
            if let Some(v) = number(lua, &t, "angle", f64::MIN)? {
                o.angle = v;
            }
            if let Some(v) = number(lua, &t, "step", 0.0)? {
                o.step = v;
            }
            if let Some(v) = number(lua, &t, "width", 0.0)? {
                o.width = v;
            }
            if let Some(v) = number(lua, &t, "widthFactor", 0.0)? {
                o.width_factor = v;
            }
            if let Some(v) = number(lua, &t, "elasticity", f64::MIN)? {
                o.elasticity = v;
            }
            if let Some(v) = number(lua, &t, "leafSize", 0.0)? {
                o.leaf_size = v;
            }
            match t.get::<Value>("tropism")? {
                Value::Nil => {}
                v => {
                    let LuaVec3(v) = mlua::FromLua::from_lua(v, lua)
                        .map_err(|e| options_error(lua, format!("'tropism': {e}")))?;
                    o.tropism = Some(v);
                }
            }
            if let Value::Table(m) = t.get::<Value>("mesh")? {
                let has_radii = !m.get::<Value>("radii")?.is_nil();
                mesh = MeshOptions::from_lua(&m).map_err(|e| options_error(lua, e))?;
                pge_tree::lua::load_texture(
                    lua,
                    "pge.turtle",
                    "mesh.texture",
                    "bark",
                    &mut mesh.texture,
                )?;
                if !has_radii {
                    mesh.radii = RadiiMode::Keep;
                }
            }
            if let Some(s) = number(lua, &t, "sides", 3.0)? {
                if s > 64.0 {
                    return Err(options_error(
                        lua,
                        format!("'sides' must be 3..64, got {s}"),
                    ));
                }
                mesh.sides = s as u32;
            }
            match t.get::<Value>("leaves")? {
                Value::Nil => {}
                Value::Table(l) => {
                    let mut l = LeafOptions::from_lua(&l).map_err(|e| options_error(lua, e))?;
                    pge_tree::lua::load_texture(
                        lua,
                        "pge.turtle",
                        "leaves.texture",
                        "leaf",
                        &mut l.texture,
                    )?;
                    leaves = Some(l);
                }
                other => {
                    return Err(options_error(
                        lua,
                        format!(
                            "'leaves' must be a table of leaf options, got {}",
                            other.type_name()
                        ),
                    ));
                }
            }
            match t.get::<Value>("colors")? {
                Value::Nil => {}
                Value::Table(c) => {
                    for v in c.sequence_values::<String>() {
                        let hex = v.map_err(|e| options_error(lua, format!("'colors': {e}")))?;
                        let m = Material::from_hex("", &hex)
                            .map_err(|e| options_error(lua, format!("'colors': {e}")))?;
                        palette.push(m.base_color);
                    }
                }
                other => {
                    return Err(options_error(
                        lua,
                        format!(
                            "'colors' must be an array of \"#rrggbb\", got {}",
                            other.type_name()
                        ),
                    ));
                }
            }
        }
        Ok(LuaTurtle {
            turtle: Turtle::new(o),
            mesh,
            leaves,
            palette,
        })
    }

    /// Meshes every skeleton drawn (one per colour index) with the tree mesher.
    pub fn model(&self, seed: u64) -> Result<Model, pge_tree::TreeError> {
        let mut model = Model::new();
        for (color, skeleton) in self.turtle.skeletons() {
            let mut mesh = self.mesh.clone();
            if !self.palette.is_empty() {
                mesh.color = self.palette[*color as usize % self.palette.len()];
            }
            let options = TreeOptions {
                mesh,
                leaves: self.leaves.clone(),
                lod: None,
            };
            let part = build_tree(skeleton, &options, seed.wrapping_add(u64::from(*color)))?;
            model.add_model(&part, Mat4::IDENTITY);
        }
        Ok(model)
    }
}

fn turtle_error(lua: &Lua, e: TurtleError) -> mlua::Error {
    script_error(lua, format!("turtle: {e}"))
}

impl UserData for LuaTurtle {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        type Cmd = fn(&mut Turtle, Option<f64>) -> Result<(), TurtleError>;
        let commands: [(&str, Cmd); 8] = [
            ("forward", Turtle::forward),
            ("move", Turtle::move_forward),
            ("turn", Turtle::turn),
            ("pitch", Turtle::pitch),
            ("roll", Turtle::roll),
            ("setWidth", Turtle::set_width),
            ("setColor", Turtle::set_color),
            ("leaf", Turtle::leaf),
        ];
        for (name, f) in commands {
            m.add_method_mut(name, move |lua, me, v: Option<f64>| {
                check_mutable(lua, &format!("turtle:{name}"))?;
                f(&mut me.turtle, v).map_err(|e| turtle_error(lua, e))
            });
        }
        m.add_method_mut("turnAround", |lua, me, ()| {
            check_mutable(lua, "turtle:turnAround")?;
            me.turtle.turn_around();
            Ok(())
        });
        m.add_method_mut("push", |lua, me, ()| {
            check_mutable(lua, "turtle:push")?;
            me.turtle.push();
            Ok(())
        });
        m.add_method_mut("pop", |lua, me, ()| {
            check_mutable(lua, "turtle:pop")?;
            me.turtle.pop().map_err(|e| turtle_error(lua, e))
        });
        m.add_method_mut("rollToHorizontal", |lua, me, ()| {
            check_mutable(lua, "turtle:rollToHorizontal")?;
            me.turtle.roll_to_horizontal();
            Ok(())
        });
        m.add_method_mut("reset", |lua, me, ()| {
            check_mutable(lua, "turtle:reset")?;
            me.turtle.reset();
            Ok(())
        });
        m.add_method("position", |_, me, ()| {
            Ok(LuaVec3(me.turtle.state().position))
        });
        m.add_method("heading", |_, me, ()| {
            Ok(LuaVec3(me.turtle.state().heading))
        });
        m.add_method("left", |_, me, ()| Ok(LuaVec3(me.turtle.state().left)));
        m.add_method("up", |_, me, ()| Ok(LuaVec3(me.turtle.state().up)));
        m.add_method("width", |_, me, ()| Ok(me.turtle.state().width));
        m.add_method("nodes", |_, me, ()| {
            Ok(me
                .turtle
                .skeletons()
                .iter()
                .map(|(_, s)| s.len())
                .sum::<usize>())
        });
        m.add_method("model", |lua, me, ()| {
            me.model(run_context(lua).seed)
                .map(LuaModel)
                .map_err(|e| script_error(lua, format!("turtle:model: {e}")))
        });
    }
}

/// The default interpretation of L-system modules by a turtle instance.
pub(crate) fn interpret(
    lua: &Lua,
    ud: &AnyUserData,
    name: &str,
    params: &[f64],
) -> mlua::Result<bool> {
    let Ok(mut t) = ud.borrow_mut::<LuaTurtle>() else {
        return Ok(false);
    };
    t.turtle
        .command(name, params)
        .map_err(|e| turtle_error(lua, e))
}

#[cfg(test)]
mod tests {
    use pge_engine::{Engine, Session, SessionOptions};

    fn session() -> Session {
        let engine = Engine::builder()
            .plugin(pge_lsystem::LSystemPlugin)
            .plugin(crate::TurtlePlugin)
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
}
