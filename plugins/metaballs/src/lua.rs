//! The Lua side: `pge.Metaballs{...}` and `pge.MarchingCubes(meta, {...})`.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use mlua::{AnyUserData, Lua, MultiValue, Table, UserData, UserDataMethods, Value};
use pge_engine::RunContext;
use pge_engine::geometry::{Material, Mesh, Model};
use pge_engine::lua::{
    Bounds, LuaMesh, LuaModel, LuaVec3, Options, finite_f32, material_from_table, memory_budget,
    run_context, script_error, vec3_arg,
};

use crate::{MarchError, MarchOptions, MarchingCubes, Metaballs};

/// `pge.Metaballs{ radius = 1 }`: a field of charged particles.
#[derive(Clone)]
pub struct LuaMetaballs(pub Rc<RefCell<Metaballs>>);

impl UserData for LuaMetaballs {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "metaball field");
        m.add_method(
            "addParticle",
            |lua, me, (pos, charge, radius): (Value, Value, Value)| {
                pge_engine::lua::check_mutable(lua, "metaballs:addParticle")?;
                let p = vec3_arg(lua, pos, "addParticle(position, charge [, radius])")?;
                let q = match charge {
                    Value::Nil => 1.0,
                    c => finite_f32(lua, &c, "addParticle: charge")?,
                };
                let r = match radius {
                    Value::Nil => None,
                    r => Some(finite_f32(lua, &r, "addParticle: radius")?),
                };
                let index =
                    me.0.borrow_mut()
                        .add_particle(p, q, r)
                        .map_err(|e| script_error(lua, format!("addParticle: {e}")))?;
                Ok(index + 1)
            },
        );
        m.add_method("calc", |lua, me, p: Value| {
            let p = vec3_arg(lua, p, "calc(position)")?;
            Ok(me.0.borrow().value(p))
        });
        m.add_method("gradient", |lua, me, p: Value| {
            let p = vec3_arg(lua, p, "gradient(position)")?;
            Ok(LuaVec3(me.0.borrow().gradient(p)))
        });
        m.add_method("getParticle", |lua, me, i: Value| {
            let n = me.0.borrow().len();
            let i = finite_f32(lua, &i, "getParticle(i)")?;
            if i.fract() != 0.0 || i < 1.0 || i as usize > n {
                return Err(script_error(
                    lua,
                    format!("getParticle({i}): there are {n} particles, numbered from 1"),
                ));
            }
            let p = me.0.borrow().particles()[i as usize - 1];
            let t = lua.create_table()?;
            t.set("position", LuaVec3(p.position))?;
            t.set("charge", p.charge)?;
            t.set("radius", p.radius)?;
            Ok(t)
        });
        m.add_method("count", |_, me, ()| Ok(me.0.borrow().len()));
        m.add_method("update", |lua, me, ()| {
            pge_engine::lua::check_mutable(lua, "metaballs:update")?;
            me.0.borrow_mut().update();
            Ok(())
        });
        m.add_method("bounds", |_, me, ()| match me.0.borrow().bounds() {
            Some((lo, hi)) => Ok((Some(LuaVec3(lo)), Some(LuaVec3(hi)))),
            None => Ok((None, None)),
        });
    }
}

/// `pge.MarchingCubes(meta, {...})`: extracts the field's surface when its model is asked
/// for, so particles added after construction are included.
pub struct LuaMarchingCubes {
    field: Rc<RefCell<Metaballs>>,
    mc: MarchingCubes,
    cache: RefCell<Option<(u64, Arc<Mesh>)>>,
}

impl LuaMarchingCubes {
    /// The surface of the field now, polygonized within `ctx`'s deadline (a limit comes back
    /// as the engine's typed error).
    fn mesh(&self, lua: &Lua, ctx: &RunContext) -> mlua::Result<Arc<Mesh>> {
        let version = self.field.borrow().version();
        if let Some((v, mesh)) = &*self.cache.borrow()
            && *v == version
        {
            return Ok(mesh.clone());
        }
        let here = pge_engine::lua::caller_location(lua);
        let mut limit = None;
        let mut interrupt = || match ctx.check_deadline(&here) {
            Ok(()) => false,
            Err(e) => {
                limit = Some(e);
                true
            }
        };
        let mut mc = self.mc.clone();
        mc.set_max_bytes(memory_budget(lua));
        let (mesh, _) = mc
            .polygonize(&self.field.borrow(), &mut interrupt)
            .map_err(|e| match (e, limit.take()) {
                (MarchError::Interrupted, Some(limit)) => mlua::Error::external(limit),
                (e, _) => script_error(lua, format!("marching cubes: {e}")),
            })?;
        let mesh = Arc::new(mesh);
        *self.cache.borrow_mut() = Some((version, mesh.clone()));
        Ok(mesh)
    }
}

impl LuaMarchingCubes {
    fn model(&self, lua: &Lua, ctx: &RunContext) -> mlua::Result<Model> {
        let mesh = self.mesh(lua, ctx)?;
        Ok(if mesh.positions.is_empty() {
            Model::new()
        } else {
            Model::from_mesh(mesh)
        })
    }
}

/// The model of a marching-cubes object grown by an algorithm, within the algorithm's run
/// context (the engine's model maker for `pge.MarchingCubes`).
pub(crate) fn model_of(
    lua: &Lua,
    ud: &AnyUserData,
    ctx: &RunContext,
) -> mlua::Result<Option<Model>> {
    match ud.borrow::<LuaMarchingCubes>() {
        Ok(mc) => mc.model(lua, ctx).map(Some),
        Err(_) => Ok(None),
    }
}

impl UserData for LuaMarchingCubes {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "marching cubes object");
        m.add_method("mesh", |lua, me, ()| {
            Ok(LuaMesh(me.mesh(lua, &run_context(lua))?))
        });
        m.add_method("model", |lua, me, ()| {
            Ok(LuaModel(me.model(lua, &run_context(lua))?))
        });
    }
}

/// `pge.MarchingCubes(meta, { resolution =, iso =, bounds =, material =, color =, maxCells = })`.
fn march_options(o: &Options) -> mlua::Result<MarchOptions> {
    let mut options = MarchOptions::default();
    match o.value("resolution")? {
        Value::Nil => {}
        v => {
            let need = format!(
                "a whole number of cells between 1 and {}",
                crate::MAX_RESOLUTION
            );
            let r = match v {
                Value::Integer(i) => i as f64,
                Value::Number(n) => n,
                other => return Err(o.wrong_type("resolution", need, &other)),
            };
            if !(r.fract() == 0.0 && r >= 1.0 && r <= f64::from(crate::MAX_RESOLUTION)) {
                return Err(o.invalid("resolution", need, r));
            }
            options.resolution = r as u32;
        }
    }
    if let Some(iso) = o.number_f32("iso", Bounds::Finite)? {
        options.iso = iso;
    }
    if let Some(cells) = o.number("maxCells", Bounds::AtLeast(1.0))? {
        options.max_cells = cells as u64;
    }
    match o.value("bounds")? {
        Value::Nil => {}
        Value::Table(t) => {
            let b = o.child("bounds", t).positional(&["min", "max"]);
            let corner = |key: &str| {
                b.vec3(key)?
                    .ok_or_else(|| b.missing(key, "a vector {x, y, z}"))
            };
            options.bounds = Some((corner("min")?, corner("max")?));
            b.finish()?;
        }
        other => return Err(o.wrong_type("bounds", "{min, max}", &other)),
    }
    let mut material = match o.value("material")? {
        Value::Nil => Material {
            name: "metaballs".into(),
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

/// Adds `pge.Metaballs` and `pge.MarchingCubes`.
pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set(
        "Metaballs",
        lua.create_function(|lua, t: Value| {
            let o = Options::new(lua, t, "pge.Metaballs")?;
            let radius = o.positive("radius")?.unwrap_or(1.0);
            o.finish()?;
            Ok(LuaMetaballs(Rc::new(RefCell::new(Metaballs::new(radius)))))
        })?,
    )?;
    pge.set(
        "MarchingCubes",
        lua.create_function(|lua, args: MultiValue| {
            let mut args = args.into_iter();
            let field = match args.next() {
                Some(Value::UserData(ud)) if ud.is::<LuaMetaballs>() => field_of(&ud)?,
                other => {
                    return Err(script_error(
                        lua,
                        format!(
                            "pge.MarchingCubes(meta, options): the first argument must be a pge.Metaballs, got {}",
                            other.map_or("nothing", |v| v.type_name())
                        ),
                    ));
                }
            };
            let options = march_options(&Options::new(
                lua,
                args.next().unwrap_or(Value::Nil),
                "pge.MarchingCubes",
            )?)?;
            let mc = MarchingCubes::new(options).map_err(|e| script_error(lua, format!("pge.MarchingCubes: {e}")))?;
            Ok(LuaMarchingCubes { field, mc, cache: RefCell::new(None) })
        })?,
    )?;
    Ok(())
}

fn field_of(ud: &AnyUserData) -> mlua::Result<Rc<RefCell<Metaballs>>> {
    Ok(ud.borrow::<LuaMetaballs>()?.0.clone())
}

#[cfg(test)]
mod tests {
    use pge_engine::{Engine, Session};

    fn session() -> (Engine, Session) {
        let engine = Engine::builder()
            .plugin(crate::MetaballsPlugin)
            .build()
            .expect("engine");
        let session = engine.session(Default::default()).expect("session");
        (engine, session)
    }

    #[test]
    fn metaballs_from_lua() {
        let (_e, s) = session();
        let (i, v, gx, charge, tris, later): (usize, f32, f32, f32, usize, usize) = s
            .eval(
                "local meta = pge.Metaballs{ radius = 1 }
                 local mc = pge.MarchingCubes(meta, { resolution = 48, iso = 0.5, color = '#ff8060',
                                                       bounds = {{-2, -2, -2}, {4, 2, 2}} })
                 local i = meta:addParticle({0, 0, 0}, 1)
                 local g = meta:gradient(pge.vec3(0.5, 0, 0))
                 local first = mc:model():triangleCount()
                 meta:addParticle(pge.vec3(3, 0, 0), 1)
                 return i, meta:calc({0, 0, 0}), g.x, meta:getParticle(1).charge, first,
                        mc:model():triangleCount()",
            )
            .expect("runs");
        assert_eq!((i, v, charge), (1, 1.0, 1.0));
        assert!(gx < 0.0);
        assert!(tris > 100);
        assert!(
            later > tris,
            "particles added after construction are included"
        );
    }

    #[test]
    fn mistakes_are_located_errors() {
        let (_e, s) = session();
        let cases = [
            (
                "local m = pge.Metaballs()\nlocal mc = pge.MarchingCubes(m, {resolution = 0})",
                "eval:2: pge.MarchingCubes: resolution must be",
            ),
            (
                "local m = pge.Metaballs()\nlocal mc = pge.MarchingCubes(m, {resolution = -3})",
                "eval:2: pge.MarchingCubes: resolution must be",
            ),
            (
                "local mc = pge.MarchingCubes({}, {})",
                "eval:1: pge.MarchingCubes(meta, options): the first argument",
            ),
            (
                "local m = pge.Metaballs()\nlocal mc = pge.MarchingCubes(m, {iso = 0})",
                "eval:2: pge.MarchingCubes: iso must be a positive",
            ),
            (
                "local m = pge.Metaballs()\nlocal mc = pge.MarchingCubes(m, {reslution = 3})",
                "eval:2: pge.MarchingCubes: unknown option 'reslution'",
            ),
            (
                "local m = pge.Metaballs()\nm:addParticle({0,0,0}, 1, -1)",
                "eval:2: addParticle: particle radius must be positive",
            ),
            (
                "local m = pge.Metaballs()\nm:getParticle(1)",
                "eval:2: getParticle(1): there are 0 particles",
            ),
            (
                "local m = pge.Metaballs()\nm:addParticle({0,0,0}, 1)\nlocal mc = pge.MarchingCubes(m, {resolution = 4000, maxCells = 1000})\nmc:model()",
                "eval:4: marching cubes: a grid of 4000x4000x4000 cells is larger than the limit",
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
