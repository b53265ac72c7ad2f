//! The Lua side: `pge.Extruder{...}` and `pge.MatrixManipulator()`.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use mlua::{FromLua, Lua, MultiValue, Table, UserData, UserDataMethods, Value};
use pge_engine::geometry::{Material, Model};
use pge_engine::lua::{
    LuaMat4, LuaMesh, LuaModel, LuaVec3, Options, conversion_message, finite_f32,
    material_from_table, memory_budget, script_error,
};

use crate::{Extruder, ExtruderOptions, MatrixManipulator};

/// A vector given as a `pge.vec3`, a table, or three numbers.
fn vector(lua: &Lua, args: &[Value], what: &str) -> mlua::Result<Vec3> {
    match args {
        [Value::Integer(_) | Value::Number(_), ..] => {
            if args.len() < 3 {
                return Err(script_error(
                    lua,
                    format!("{what}: expected x, y, z or a vector"),
                ));
            }
            Ok(Vec3::new(
                finite_f32(lua, &args[0], what)?,
                finite_f32(lua, &args[1], what)?,
                finite_f32(lua, &args[2], what)?,
            ))
        }
        [v, ..] => LuaVec3::from_lua(v.clone(), lua)
            .map(|v| v.0)
            .map_err(|e| script_error(lua, format!("{what}: {}", conversion_message(&e)))),
        [] => Err(script_error(
            lua,
            format!("{what}: expected x, y, z or a vector"),
        )),
    }
}

fn colour(lua: &Lua, v: &Value, what: &str) -> mlua::Result<Vec4> {
    match v {
        Value::String(s) => {
            let s = s.to_str()?;
            Material::from_hex("", &s)
                .map(|m| Vec4::from(m.base_color))
                .map_err(|e| script_error(lua, format!("{what}: {e}")))
        }
        other => Err(script_error(
            lua,
            format!(
                "{what}: expected a colour \"#rrggbb\", got {}",
                other.type_name()
            ),
        )),
    }
}

/// What a `pge.MatrixManipulator` userdata edits: its own matrix, or an extruder's path or
/// shape matrix (live: changing it moves the extruder).
#[derive(Clone)]
enum Target {
    Own(Rc<RefCell<MatrixManipulator>>),
    Path(Rc<RefCell<Extruder>>),
    Shape(Rc<RefCell<Extruder>>),
}

/// `pge.MatrixManipulator()` and what `getPathMatrix` / `getShapeMatrix` return.
#[derive(Clone)]
pub struct LuaMatrixManipulator(Target);

impl LuaMatrixManipulator {
    fn with<R>(&self, f: impl FnOnce(&mut MatrixManipulator) -> R) -> R {
        match &self.0 {
            Target::Own(m) => f(&mut m.borrow_mut()),
            Target::Path(e) => f(e.borrow_mut().path_mut()),
            Target::Shape(e) => f(e.borrow_mut().shape_matrix_mut()),
        }
    }
}

/// Refuses a change while an L-system's rewriting rule runs (`this` is read-only there).
fn guard(lua: &Lua, what: &str) -> mlua::Result<()> {
    pge_engine::lua::check_mutable(lua, what)
}

fn matrix_op(
    lua: &Lua,
    me: &LuaMatrixManipulator,
    what: &str,
    f: impl FnOnce(&mut MatrixManipulator) -> Result<(), crate::MatrixError>,
) -> mlua::Result<()> {
    // An extruder's matrices belong to it; a free-standing matrix is a calculator that a
    // rewriting rule may use.
    if !matches!(me.0, Target::Own(_)) {
        guard(lua, &format!("matrix:{what}"))?;
    }
    me.with(f)
        .map_err(|e| script_error(lua, format!("{what}: {e}")))
}

impl UserData for LuaMatrixManipulator {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "matrix manipulator");
        m.add_method("push", |lua, me, ()| {
            matrix_op(lua, me, "push", |m| m.push())
        });
        m.add_method("pop", |lua, me, ()| matrix_op(lua, me, "pop", |m| m.pop()));
        m.add_method("reset", |lua, me, ()| {
            if !matches!(me.0, Target::Own(_)) {
                guard(lua, "matrix:reset")?;
            }
            me.with(|m| m.reset());
            Ok(())
        });
        m.add_method("rotate", |lua, me, args: MultiValue| {
            let args: Vec<Value> = args.into_iter().collect();
            let deg = finite_f32(
                lua,
                args.first().unwrap_or(&Value::Nil),
                "rotate(degrees, axis)",
            )?;
            let axis = vector(lua, &args[1.min(args.len())..], "rotate(degrees, axis)")?;
            matrix_op(lua, me, "rotate", |m| m.rotate(axis, deg))
        });
        for (name, axis) in [
            ("rotateX", Vec3::X),
            ("rotateY", Vec3::Y),
            ("rotateZ", Vec3::Z),
        ] {
            m.add_method(name, move |lua, me, deg: Value| {
                let deg = finite_f32(lua, &deg, name)?;
                matrix_op(lua, me, name, |m| m.rotate(axis, deg))
            });
        }
        m.add_method("scale", |lua, me, args: MultiValue| {
            let args: Vec<Value> = args.into_iter().collect();
            let factors = match args.as_slice() {
                [v @ (Value::Integer(_) | Value::Number(_))] => {
                    Vec3::splat(finite_f32(lua, v, "scale")?)
                }
                rest => vector(lua, rest, "scale(s) or scale(x, y, z)")?,
            };
            matrix_op(lua, me, "scale", |m| m.scale(factors))
        });
        for (name, axis) in [("scaleX", 0usize), ("scaleY", 1), ("scaleZ", 2)] {
            m.add_method(name, move |lua, me, f: Value| {
                let f = finite_f32(lua, &f, name)?;
                let mut v = Vec3::ONE;
                v[axis] = f;
                matrix_op(lua, me, name, |m| m.scale(v))
            });
        }
        m.add_method("translate", |lua, me, args: MultiValue| {
            let args: Vec<Value> = args.into_iter().collect();
            let v = vector(lua, &args, "translate")?;
            matrix_op(lua, me, "translate", |m| m.translate(v))
        });
        m.add_method("advance", |lua, me, d: Value| {
            let d = finite_f32(lua, &d, "advance")?;
            matrix_op(lua, me, "advance", |m| m.advance(d))
        });
        m.add_method("getMatrix", |_, me, ()| {
            Ok(LuaMat4(me.with(|m| m.matrix())))
        });
        m.add_method("setMatrix", |lua, me, mat: Value| {
            let mat = LuaMat4::from_lua(mat, lua)
                .map_err(|e| script_error(lua, format!("setMatrix: {}", conversion_message(&e))))?;
            matrix_op(lua, me, "setMatrix", |m| m.set_matrix(mat.0))
        });
        m.add_method("transformPoint", |lua, me, args: MultiValue| {
            let args: Vec<Value> = args.into_iter().collect();
            let p = vector(lua, &args, "transformPoint")?;
            Ok(LuaVec3(me.with(|m| m.transform_point(p))))
        });
        m.add_method("position", |_, me, ()| {
            Ok(LuaVec3(me.with(|m| m.transform_point(Vec3::ZERO))))
        });
        m.add_method("depth", |_, me, ()| Ok(me.with(|m| m.depth())));
    }
}

/// `pge.Extruder{...}`: the extrusion modeller, shared with the matrices it hands out.
#[derive(Clone)]
pub struct LuaExtruder(pub Rc<RefCell<Extruder>>);

fn extruder_op(
    lua: &Lua,
    me: &LuaExtruder,
    what: &str,
    f: impl FnOnce(&mut Extruder) -> Result<(), crate::ExtruderError>,
) -> mlua::Result<()> {
    guard(lua, &format!("extruder:{what}"))?;
    f(&mut me.0.borrow_mut()).map_err(|e| script_error(lua, format!("{what}: {e}")))
}

impl UserData for LuaExtruder {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "extruder");
        m.add_method("clearShape", |lua, me, ()| {
            guard(lua, "extruder:clearShape")?;
            me.0.borrow_mut().clear_shape();
            Ok(())
        });
        m.add_method("addPoint2", |lua, me, args: MultiValue| {
            let args: Vec<Value> = args.into_iter().collect();
            let p = match args.as_slice() {
                [x @ (Value::Integer(_) | Value::Number(_)), z, ..] => Vec2::new(
                    finite_f32(lua, x, "addPoint2(x, z)")?,
                    finite_f32(lua, z, "addPoint2(x, z)")?,
                ),
                [Value::Table(t)] => {
                    let (x, z): (Value, Value) = (t.raw_get(1)?, t.raw_get(2)?);
                    Vec2::new(
                        finite_f32(lua, &x, "addPoint2{x, z}")?,
                        finite_f32(lua, &z, "addPoint2{x, z}")?,
                    )
                }
                _ => return Err(script_error(lua, "addPoint2: expected x, z (two numbers)")),
            };
            extruder_op(lua, me, "addPoint2", |e| e.add_point2(p))
        });
        m.add_method("addPoint3", |lua, me, args: MultiValue| {
            let args: Vec<Value> = args.into_iter().collect();
            let p = vector(lua, &args, "addPoint3")?;
            extruder_op(lua, me, "addPoint3", |e| e.add_point3(p))
        });
        m.add_method("polygon", |lua, me, (n, r): (Value, Value)| {
            let sides = finite_f32(lua, &n, "polygon(sides, radius)")?;
            if sides.fract() != 0.0 || sides < 0.0 {
                return Err(script_error(
                    lua,
                    format!("polygon: sides must be a whole number, got {sides}"),
                ));
            }
            let radius = finite_f32(lua, &r, "polygon(sides, radius)")?;
            extruder_op(lua, me, "polygon", |e| {
                e.set_polygon(sides as usize, radius)
            })
        });
        m.add_method("pointCount", |_, me, ()| Ok(me.0.borrow().shape().len()));
        m.add_method("extrude", |lua, me, d: Value| {
            let d = finite_f32(lua, &d, "extrude(distance)")?;
            extruder_op(lua, me, "extrude", |e| e.extrude(d))
        });
        m.add_method("start", |lua, me, ()| {
            guard(lua, "extruder:start")?;
            me.0.borrow_mut().start();
            Ok(())
        });
        m.add_method("finish", |lua, me, ()| {
            guard(lua, "extruder:finish")?;
            me.0.borrow_mut().finish();
            Ok(())
        });
        m.add_method("push", |lua, me, ()| {
            extruder_op(lua, me, "push", |e| e.push())
        });
        m.add_method("pop", |lua, me, ()| {
            extruder_op(lua, me, "pop", |e| e.pop())
        });
        m.add_method("getPathMatrix", |_, me, ()| {
            Ok(LuaMatrixManipulator(Target::Path(me.0.clone())))
        });
        m.add_method("getShapeMatrix", |_, me, ()| {
            Ok(LuaMatrixManipulator(Target::Shape(me.0.clone())))
        });
        m.add_method("setColor", |lua, me, c: Value| {
            let c = colour(lua, &c, "setColor")?;
            extruder_op(lua, me, "setColor", |e| e.set_color(c))
        });
        m.add_method("position", |_, me, ()| {
            Ok(LuaVec3(me.0.borrow().path().transform_point(Vec3::ZERO)))
        });
        m.add_method("mesh", |_, me, ()| {
            Ok(LuaMesh(Arc::new(me.0.borrow().mesh())))
        });
        m.add_method("model", |_, me, ()| Ok(LuaModel(model_of(&me.0.borrow()))));
        // The thesis' name for the finished geometry.
        m.add_method("getNode", |_, me, ()| {
            Ok(LuaModel(model_of(&me.0.borrow())))
        });
    }
}

fn model_of(e: &Extruder) -> Model {
    let mesh = e.mesh();
    if mesh.positions.is_empty() {
        Model::new()
    } else {
        Model::from_mesh(mesh)
    }
}

/// `pge.Extruder{ smooth =, caps =, material =, color = }`.
fn options(o: &Options) -> mlua::Result<ExtruderOptions> {
    let mut options = ExtruderOptions::default();
    if let Some(smooth) = o.boolean("smooth")? {
        options.smooth = smooth;
    }
    if let Some(caps) = o.boolean("caps")? {
        options.caps = caps;
    }
    let mut material = match o.value("material")? {
        Value::Nil => Material {
            name: "extrusion".into(),
            ..Material::default()
        },
        Value::Table(mt) => material_from_table(o.lua(), &mt)?,
        other => return Err(o.wrong_type("material", "a table", &other)),
    };
    if let Some(c) = o.color("color")? {
        material.base_color = c;
    }
    o.finish()?;
    options.material = Arc::new(material);
    Ok(options)
}

/// Adds `pge.Extruder` and `pge.MatrixManipulator`.
pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set(
        "Extruder",
        lua.create_function(|lua, t: Value| {
            let mut options = options(&Options::new(lua, t, "pge.Extruder")?)?;
            options.max_points = memory_budget(lua) / Extruder::MESH_BYTES_PER_POINT;
            Ok(LuaExtruder(Rc::new(RefCell::new(Extruder::new(options)))))
        })?,
    )?;
    pge.set(
        "MatrixManipulator",
        lua.create_function(|_, ()| {
            Ok(LuaMatrixManipulator(Target::Own(Rc::new(RefCell::new(
                MatrixManipulator::new(),
            )))))
        })?,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use pge_engine::{Engine, Session};

    fn session() -> (Engine, Session) {
        let engine = Engine::builder()
            .plugin(crate::ExtruderPlugin)
            .build()
            .expect("engine");
        let session = engine.session(Default::default()).expect("session");
        (engine, session)
    }

    #[test]
    fn a_script_extrudes_and_shares_matrices() {
        let (_e, s) = session();
        let (tris, x, y): (usize, f32, f32) = s
            .eval(
                "local e = pge.Extruder{ color = '#ff0000' }
                 e:addPoint2(1, 1) e:addPoint2(1, -1) e:addPoint2(-1, -1) e:addPoint2(-1, 1)
                 local path = e:getPathMatrix()
                 e:extrude(2)
                 path:rotateZ(90)
                 e:getShapeMatrix():scale(0.5)
                 e:extrude(1)
                 local p = e:position()
                 return e:model():triangleCount(), p.x, p.y",
            )
            .expect("runs");
        assert_eq!(tris, 2 * 4 * 2 + 4);
        assert!(
            (x + 1.0).abs() < 1e-5 && (y - 2.0).abs() < 1e-5,
            "({x}, {y})"
        );
    }

    #[test]
    fn matrix_manipulator_in_lua() {
        let (_e, s) = session();
        let (x, y, z, depth): (f32, f32, f32, usize) = s
            .eval(
                "local m = pge.MatrixManipulator()
                 m:translate(1, 0, 0) m:push() m:rotate(90, {0, 0, 1}) m:advance(2)
                 m:scale(2) m:scaleX(3) m:rotateX(10) m:rotateY(10)
                 m:pop() m:push()
                 local p = m:transformPoint(pge.vec3(0, 1, 0))
                 return p.x, p.y, p.z, m:depth()",
            )
            .expect("runs");
        assert_eq!((x, y, z, depth), (1.0, 1.0, 0.0, 1));
    }

    #[test]
    fn rewriting_rules_may_not_change_the_extruder() {
        // The L-system enters the engine's read-only phase around its rewriting rules (the
        // workspace's `tests/plugins.rs` runs one); a free matrix stays writable.
        let (_e, s) = session();
        s.eval::<()>("e = pge.Extruder()\ne:polygon(4, 1)")
            .expect("runs");
        let phase = pge_engine::lua::read_only_phase(s.lua());
        phase.enter("A".into());
        s.eval::<()>("local m = pge.MatrixManipulator()\nm:advance(1)")
            .expect("a free matrix is fine");
        let err = s
            .eval::<()>("\ne:extrude(1)")
            .expect_err("extrude in an RRule")
            .to_string();
        phase.leave();
        assert!(
            err.starts_with("eval:2: RRule 'A': extruder:extrude is not allowed"),
            "{err}"
        );
        s.eval::<()>("e:extrude(1)").expect("writable again");
    }

    #[test]
    fn mistakes_are_located_errors() {
        let (_e, s) = session();
        let cases = [
            (
                "local e = pge.Extruder()\ne:addPoint2(0, 0)\ne:extrude(1)",
                "eval:3: extrude: the shape has 1 point(s)",
            ),
            (
                "local m = pge.MatrixManipulator()\nm:pop()",
                "eval:2: pop: pop without a matching push",
            ),
            (
                "local e = pge.Extruder()\n\ne:pop()",
                "eval:3: pop: pop without a matching push",
            ),
            (
                "local e = pge.Extruder()\ne:getPathMatrix():pop()",
                "eval:2: pop: pop without",
            ),
            (
                "local e = pge.Extruder{ smoth = true }",
                "eval:1: pge.Extruder: unknown option 'smoth'",
            ),
            (
                "local e = pge.Extruder()\ne:addPoint2('a', 1)",
                "eval:2: addPoint2",
            ),
            (
                "local e = pge.Extruder()\ne:polygon(4, 1)\ne:extrude(-2)",
                "eval:3: extrude: extrusion distance -2 is negative",
            ),
            (
                "local e = pge.Extruder()\ne:setColor('blue')",
                "eval:2: setColor: 'blue' is not a colour",
            ),
            (
                "local m = pge.MatrixManipulator()\nm:rotate(10, 0, 0, 0)",
                "eval:2: rotate: the rotation axis has zero length",
            ),
        ];
        for (code, expected) in cases {
            let err = s.eval::<()>(code).expect_err(code).to_string();
            assert!(
                err.starts_with(expected),
                "{code}\n  gave: {err}\n  want: {expected}"
            );
        }
    }
}
