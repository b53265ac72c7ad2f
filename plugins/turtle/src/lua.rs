//! `pge.turtle{...}`: the turtle as a Lua object and as the L-systems' default interpretation.

use std::sync::Arc;

use glam::{Mat4, Vec4};
use mlua::{AnyUserData, Lua, UserData, UserDataMethods, Value};
use pge_engine::RunContext;
use pge_engine::geometry::{Material, Mesh, Model, Skeleton};
use pge_engine::lua::{
    Bounds, KeyStyle, LuaModel, LuaVec3, Options, check_mutable, run_context, script_error,
};
use pge_tree::{LeafOptions, MeshOptions, RadiiMode, TreeOptions, build_tree};

use crate::turtle::{Turtle, TurtleError, TurtleOptions};

/// A turtle in Lua, with the options its model is meshed with.
pub struct LuaTurtle {
    /// The turtle.
    pub turtle: Turtle,
    mesh: MeshOptions,
    leaves: Option<LeafOptions>,
    lod: Option<pge_lod::LodOptions>,
    palette: Vec<[f32; 4]>,
}

impl LuaTurtle {
    /// `pge.turtle{...}`: reads the options (nil for the defaults).
    pub fn new(lua: &Lua, options: Value) -> mlua::Result<LuaTurtle> {
        let o = Options::new(lua, options, "pge.turtle")?.style(KeyStyle::Quoted);
        LuaTurtle::from_options(&o)
    }

    /// Reads `pge.turtle{...}` options.
    pub fn from_options(o: &Options) -> mlua::Result<LuaTurtle> {
        let mut t = TurtleOptions::default();
        let mut mesh = MeshOptions {
            radii: RadiiMode::Keep,
            ..MeshOptions::default()
        };
        let any = Bounds::Finite;
        let at_least_0 = Bounds::AtLeast(0.0);
        if let Some(v) = o.number_f32("angle", any)? {
            t.angle = v;
        }
        if let Some(v) = o.number_f32("step", at_least_0)? {
            t.step = v;
        }
        if let Some(v) = o.number_f32("width", at_least_0)? {
            t.width = v;
        }
        if let Some(v) = o.number_f32("widthFactor", at_least_0)? {
            t.width_factor = v;
        }
        if let Some(v) = o.vec3("tropism")? {
            t.tropism = Some(v);
        }
        if let Some(v) = o.number_f32("elasticity", any)? {
            t.elasticity = v;
        }
        if let Some(m) = o.table_options("mesh")? {
            let has_radii = !m.value("radii")?.is_nil();
            pge_tree::lua::read_mesh(&m, &mut mesh)?;
            pge_tree::lua::load_texture(o, "mesh.texture", "bark", &mut mesh.texture)?;
            if !has_radii {
                mesh.radii = RadiiMode::Keep;
            }
        }
        if let Some(sides) = o.integer("sides", 3..=64)? {
            mesh.sides = sides as u32;
        }
        let leaves = match o.table_options("leaves")? {
            Some(l) => {
                let mut l = pge_tree::lua::leaf_options(&l)?;
                pge_tree::lua::load_texture(o, "leaves.texture", "leaf", &mut l.texture)?;
                Some(l)
            }
            None => None,
        };
        let lod = pge_lod::lua::lod_options(o)?;
        if let Some(v) = o.number_f32("leafSize", at_least_0)? {
            t.leaf_size = v;
        }
        let mut palette = Vec::new();
        match o.value("colors")? {
            Value::Nil => {}
            Value::Table(c) => {
                for (k, v) in c.sequence_values::<Value>().enumerate() {
                    let key = format!("colors[{}]", k + 1);
                    let color = match v? {
                        Value::String(s) => {
                            let hex = s.to_string_lossy();
                            Material::from_hex("", &hex)
                                .map_err(|_| {
                                    o.invalid(&key, "a colour \"#rrggbb\"", format!("\"{hex}\""))
                                })?
                                .base_color
                        }
                        other => return Err(o.wrong_type(&key, "a colour \"#rrggbb\"", &other)),
                    };
                    palette.push(color);
                }
            }
            other => return Err(o.wrong_type("colors", "an array of \"#rrggbb\"", &other)),
        }
        o.finish()?;
        Ok(LuaTurtle {
            turtle: Turtle::new(t),
            mesh,
            leaves,
            lod,
            palette,
        })
    }

    /// Meshes every skeleton drawn (one per colour index) with the tree mesher, then joins
    /// them: one bark mesh, its colour index's palette colour in the vertices (times a
    /// white-shaded bark texture, so one texture serves every colour) and every colour's
    /// skeleton in one, and one leaf mesh. With `lod`, whose leaf tables count each tree's
    /// own index buffer, every colour keeps its own meshes (colour-baked bark textures).
    pub fn model(&self, seed: u64) -> Result<Model, pge_tree::TreeError> {
        let mut parts = Vec::with_capacity(self.turtle.skeletons().len());
        for (color, skeleton) in self.turtle.skeletons() {
            let mut mesh = self.mesh.clone();
            let tint = (!self.palette.is_empty())
                .then(|| self.palette[*color as usize % self.palette.len()]);
            if let Some(tint) = tint {
                mesh.color = if self.lod.is_some() { tint } else { [1.0; 4] };
            }
            let options = TreeOptions {
                mesh,
                leaves: self.leaves.clone(),
                lod: self.lod.clone(),
            };
            let part = build_tree(skeleton, &options, seed.wrapping_add(u64::from(*color)))?;
            parts.push((part, tint));
        }
        let mut model = Model::new();
        if self.lod.is_some() {
            for (part, _) in &parts {
                model.add_model(part, Mat4::IDENTITY);
            }
            return Ok(model);
        }
        let (mut bark, mut leaves): (Option<Mesh>, Option<Mesh>) = (None, None);
        let mut skeleton = Skeleton::new();
        for (part, tint) in &parts {
            for mesh in &part.meshes {
                let mut mesh = (**mesh).clone();
                let joined = match mesh.skeleton.take() {
                    Some(s) => {
                        skeleton.append(&s, &Mat4::IDENTITY);
                        if let Some(tint) = tint {
                            mesh.colors = vec![Vec4::from_array(*tint); mesh.positions.len()];
                        }
                        &mut bark
                    }
                    None => &mut leaves,
                };
                match joined {
                    Some(all) => all.append(&mesh),
                    None => *joined = Some(mesh),
                }
            }
            model.stats.merge(&part.stats);
        }
        if let Some(mut bark) = bark {
            bark.skeleton = Some(Arc::new(skeleton));
            model.add_mesh(bark, Mat4::IDENTITY);
        }
        if let Some(leaves) = leaves {
            model.add_mesh(leaves, Mat4::IDENTITY);
        }
        Ok(model)
    }
}

fn turtle_error(lua: &Lua, e: TurtleError) -> mlua::Error {
    script_error(lua, format!("turtle: {e}"))
}

impl UserData for LuaTurtle {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "turtle");
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
        m.add_method("skeleton", |lua, me, ()| {
            // Every colour's skeleton joined into one (each keeps its roots).
            let mut joined = pge_engine::geometry::Skeleton::new();
            for (_, s) in me.turtle.skeletons() {
                joined.append(s, &Mat4::IDENTITY);
            }
            pge_engine::lua::LuaSkeleton::new(joined).into_lua_charged(lua)
        });
        m.add_method("model", |lua, me, ()| {
            me.model(run_context(lua).seed)
                .map(LuaModel)
                .map_err(|e| match e {
                    pge_tree::TreeError::Lod(pge_lod::LodError::Limit(limit)) => {
                        mlua::Error::external(*limit)
                    }
                    other => script_error(lua, format!("turtle:model: {other}")),
                })
        });
    }
}

/// The model of a turtle grown by an algorithm, with the algorithm's run context (the
/// engine's model maker for turtles).
pub(crate) fn model_of(
    lua: &Lua,
    ud: &AnyUserData,
    ctx: &RunContext,
) -> mlua::Result<Option<Model>> {
    let Ok(t) = ud.borrow::<LuaTurtle>() else {
        return Ok(None);
    };
    t.model(ctx.seed)
        .map(Some)
        .map_err(|e| script_error(lua, format!("turtle:model: {e}")))
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
    use pge_engine::lua::{interpreters, read_only_phase};
    use pge_engine::{Engine, Session, SessionOptions};

    // Turtles inside L-systems are tested with both plugins in the workspace's
    // `tests/plugins.rs`; here the turtle alone and the engine services it fills.
    fn session() -> Session {
        let engine = Engine::builder()
            .plugin(crate::TurtlePlugin)
            .build()
            .expect("engine");
        engine.session(SessionOptions::default()).expect("session")
    }

    #[test]
    fn turtle_methods() {
        let s = session();
        let y: f64 = s
            .eval(
                "local t = pge.turtle{} t:forward(2) t:turn(90) t:forward(1) t:push() t:pitch(90) \
                 t:forward() t:pop() return t:position().y",
            )
            .expect("runs");
        assert!((y - 2.0).abs() < 1e-6);
    }

    #[test]
    fn bad_options_are_located_errors() {
        let s = session();
        let e = s
            .eval_value("return pge.turtle{ angel = 3 }")
            .expect_err("typo")
            .to_string();
        assert!(e.contains("unknown option 'angel'"), "{e}");
        let e = s
            .eval_value("\nreturn pge.turtle{ angle = 0/0 }")
            .expect_err("nan")
            .to_string();
        assert_eq!(
            e,
            "eval:2: pge.turtle: 'angle' must be a finite number, got NaN"
        );
        let e = s
            .eval_value("return pge.turtle{ sides = 100 }")
            .expect_err("range")
            .to_string();
        assert_eq!(
            e,
            "eval:1: pge.turtle: 'sides' must be an integer between 3 and 64, got 100"
        );
    }

    #[test]
    fn the_turtle_fills_the_engine_registry() {
        let s = session();
        let lua = s.lua();
        let Some(mlua::Value::UserData(ud)) = pge_engine::lua::default_instance(lua).expect("made")
        else {
            panic!("a turtle");
        };
        for f in interpreters(lua) {
            assert!(f(lua, &ud, "F", &[2.0]).expect("interprets"));
        }
        let t = ud.borrow::<crate::LuaTurtle>().expect("a turtle");
        assert_eq!(t.turtle.state().position.y, 2.0);
        drop(t);
        // Changing a turtle during a rewriting rule is refused.
        s.lua().globals().set("t", ud).expect("global");
        read_only_phase(lua).enter("A".into());
        let e = s.eval::<()>("t:forward(1)").expect_err("read-only");
        read_only_phase(lua).leave();
        assert!(
            e.to_string()
                .starts_with("eval:1: RRule 'A': turtle:forward is not allowed"),
            "{e}"
        );
    }
}
