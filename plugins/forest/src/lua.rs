//! The Lua side: `pge.Forest{...}` with `:terrain`, `:scatter`, `:height`, `:normal`,
//! `:instances`, `:tiles` and `:selectTile`. A thin adapter: it reads and checks options
//! (errors at the calling line name the option and what it needs) into a [`ForestSpec`],
//! and returns a [`ForestRun`] whose script species are grown by a [`SessionGrower`]: each
//! variant in a session of its own, created by the engine that created the forest's session
//! (same sandbox and limits), handed over when the plugin registers.

mod grower;
mod options;

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use mlua::{Lua, Table, UserData, UserDataMethods, Value};
use pge_engine::lua::{
    AlgorithmHandle, LuaVec3, caller_location, finite_number, run_context, script_error,
};
use pge_engine::{Engine, Error, Plugin};

use crate::{
    ForestConfig, ForestError, ForestRun, ForestSpec, SpeciesGrower, VariantCache, VariantSharing,
    check_budget, levels,
};
pub use grower::SessionGrower;
use options::{new_forest, scatter, terrain};

/// Adds `pge.Forest` to every session. Its configuration (a variant cache, the sharing of
/// variants between tiles) is given here, when the engine is built, and reaches every forest
/// run of every session.
#[derive(Clone, Debug, Default)]
pub struct ForestPlugin {
    config: ForestConfig,
}

impl ForestPlugin {
    /// Forests keep the variants their species scripts grow in `cache` and read them back
    /// from there (`pge run --variant-cache DIR`); the output is the same.
    #[must_use]
    pub fn with_variant_cache(cache: VariantCache) -> ForestPlugin {
        ForestPlugin {
            config: ForestConfig {
                cache: Some(cache),
                sharing: None,
            },
        }
    }

    /// Forests write only their shared variants, or refer to them instead of growing them
    /// (`pge run --variants-out DIR`, `--variants DIR`; see [`VariantSharing`]).
    #[must_use]
    pub fn sharing(mut self, sharing: VariantSharing) -> ForestPlugin {
        self.config.sharing = Some(sharing);
        self
    }

    /// Sets `pge.Forest`, whose runs grow species scripts with `grower`.
    fn install(
        &self,
        lua: &Lua,
        pge: &Table,
        grower: Option<Arc<dyn SpeciesGrower>>,
    ) -> mlua::Result<()> {
        let setup = Rc::new(Setup {
            config: self.config.clone(),
            grower,
        });
        pge.set(
            "Forest",
            lua.create_function(move |lua, v: Value| new_forest(lua, v, setup.clone()))?,
        )
    }
}

impl Plugin for ForestPlugin {
    fn name(&self) -> &str {
        "forest"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["Forest"]
    }

    /// For a Lua state no engine created: forests whose species are scripts cannot grow.
    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        self.install(lua, pge, None)
    }

    fn register_in(&self, engine: &Engine, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        let grower = SessionGrower::for_session(engine.clone(), lua);
        self.install(lua, pge, Some(Arc::new(grower)))
    }
}

/// What every forest of a session runs with: the plugin's configuration and the grower of
/// species scripts.
struct Setup {
    config: ForestConfig,
    grower: Option<Arc<dyn SpeciesGrower>>,
}

impl Setup {
    /// The run of `spec` with this setup.
    fn run(&self, spec: ForestSpec) -> ForestRun {
        let run = ForestRun::new(spec).config(self.config.clone());
        match &self.grower {
            Some(grower) => run.grower(grower.clone()),
            None => run,
        }
    }
}

/// An error of the forest `spec` describes, at the line of its `pge.Forest{...}`, typed.
fn at_forest(spec: &ForestSpec, e: &ForestError) -> mlua::Error {
    mlua::Error::external(Error::script(spec.origin(), e.to_string()))
}

/// A forest being described by a script (`pge.Forest{...}`); returning it runs it.
#[derive(Clone)]
pub struct LuaForest {
    spec: Rc<RefCell<ForestSpec>>,
    setup: Rc<Setup>,
}
impl LuaForest {
    /// The forest's description, or a located error when a method of the forest runs while
    /// another holds it (a density or species function calling its own forest's methods).
    fn spec(&self, lua: &Lua, method: &str) -> mlua::Result<std::cell::Ref<'_, ForestSpec>> {
        self.spec.try_borrow().map_err(|_| busy(lua, method))
    }

    /// [`LuaForest::spec`], to change it.
    fn spec_mut(&self, lua: &Lua, method: &str) -> mlua::Result<std::cell::RefMut<'_, ForestSpec>> {
        self.spec.try_borrow_mut().map_err(|_| busy(lua, method))
    }
}

fn busy(lua: &Lua, method: &str) -> mlua::Error {
    script_error(
        lua,
        format!(
            "forest:{method}: the forest is busy laying out or growing itself (a density or \
             species function cannot call its own forest's methods)"
        ),
    )
}

impl UserData for LuaForest {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("terrain", |lua, me, v: Value| {
            terrain(lua, &mut *me.spec_mut(lua, "terrain")?, v)?;
            Ok(me.clone())
        });
        m.add_method("scatter", |lua, me, v: Value| {
            scatter(lua, &mut *me.spec_mut(lua, "scatter")?, v)?;
            Ok(me.clone())
        });
        m.add_method("height", |lua, me, (x, z): (Value, Value)| {
            let x = finite_number(lua, &x, "forest:height: x")?;
            let z = finite_number(lua, &z, "forest:height: z")?;
            Ok(me.spec(lua, "height")?.forest().terrain.height(x, z))
        });
        m.add_method("normal", |lua, me, (x, z): (Value, Value)| {
            let x = finite_number(lua, &x, "forest:normal: x")?;
            let z = finite_number(lua, &z, "forest:normal: z")?;
            Ok(LuaVec3(
                me.spec(lua, "normal")?.forest().terrain.normal(x, z),
            ))
        });
        m.add_method("selectTile", |lua, me, (i, j): (Value, Value)| {
            let i = finite_number(lua, &i, "forest:selectTile: i")?;
            let j = finite_number(lua, &j, "forest:selectTile: j")?;
            if i < 0.0 || j < 0.0 || i.fract() != 0.0 || j.fract() != 0.0 {
                return Err(script_error(
                    lua,
                    format!("forest:selectTile: i and j must be integers >= 0, got {i}, {j}"),
                ));
            }
            let mut spec = me.spec_mut(lua, "selectTile")?;
            if let Err(e) = spec.select_tile(i as usize, j as usize) {
                return Err(at_forest(&spec, &e));
            }
            Ok(me.clone())
        });
        m.add_method("tiles", |lua, me, ()| {
            let spec = me.spec(lua, "tiles")?;
            let tiles = spec.tiles(&run_context(lua).budget).map_err(|e| match e {
                ForestError::Script(e) => mlua::Error::external(e.at(caller_location(lua))),
                other => at_forest(&spec, &other),
            })?;
            let out = lua.create_table()?;
            for t in tiles {
                let e = lua.create_table()?;
                e.set("i", t.i)?;
                e.set("j", t.j)?;
                e.set("min", lua.create_sequence_from(t.rect.min)?)?;
                e.set("max", lua.create_sequence_from(t.rect.max)?)?;
                out.push(e)?;
            }
            Ok(out)
        });
        m.add_method("instances", |lua, me, ()| {
            let spec = me.spec(lua, "instances")?;
            let layout = spec
                .forest()
                .layout_within(spec.tile(), &run_context(lua), &caller_location(lua))
                .map_err(|e| match e {
                    ForestError::Script(e) => mlua::Error::external(e),
                    other => script_error(lua, format!("forest:instances: {other}")),
                })?;
            // With a camera, each instance's leaves: the variants are grown to know theirs.
            let (leaves, lods) = if let Some(camera) = &spec.lod.camera {
                check_budget(spec.forest(), camera)
                    .map_err(|e| script_error(lua, format!("forest:instances: {e}")))?;
                let run = me.setup.run(spec.clone());
                let typed = |e: ForestError| mlua::Error::external(run.engine_error(e));
                let grown = run.grow(&layout, &run_context(lua)).map_err(typed)?;
                let leaves = run
                    .budgeted_leaves(&layout, &grown, &run_context(lua))
                    .map_err(typed)?;
                (leaves.unwrap_or_default(), levels(&grown))
            } else {
                (Vec::new(), Vec::new())
            };
            let out = lua.create_table_with_capacity(layout.instances.len(), 0)?;
            for (k, i) in layout.instances.iter().enumerate() {
                let e = lua.create_table_with_capacity(0, 7)?;
                let lod = lods
                    .get(i.layer as usize)
                    .and_then(|l| l.get(i.variant as usize))
                    .copied()
                    .flatten();
                if let (Some(Some(count)), Some(lod)) = (leaves.get(k), lod) {
                    e.set("leaves", *count)?;
                    let level = if *count > 0 {
                        i64::from(*count) - i64::from(lod.roots)
                    } else {
                        -1
                    };
                    e.set("level", level)?;
                }
                e.set(
                    "species",
                    spec.forest().layers[i.layer as usize].name.as_str(),
                )?;
                e.set("variant", i.variant)?;
                e.set("position", LuaVec3(glam::Vec3::from_array(i.position)))?;
                e.set("yaw", f64::from(i.yaw).to_degrees())?;
                e.set("scale", i.scale)?;
                out.push(e)?;
            }
            Ok(out)
        });
        m.add_method("algorithm", |lua, me, ()| {
            let run = me.setup.run(me.spec(lua, "algorithm")?.clone());
            Ok(AlgorithmHandle::new(Box::new(run)))
        });
    }
}
