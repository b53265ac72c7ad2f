//! The Lua side: `pge.Forest{...}` with `:terrain`, `:scatter`, `:height`, `:normal`,
//! `:instances`, `:tiles` and `:selectTile`. A thin adapter: it reads and checks options
//! (errors at the calling line name the option and what it needs), hands plain values to
//! [`Forest`], and grows the variants of a species script in parallel, each in a session of
//! its own created by the same engine (same sandbox and limits).

mod algorithm;
mod options;

use std::cell::RefCell;
use std::rc::Rc;

use mlua::{Function, Lua, Table, UserData, UserDataMethods, Value};
use pge_engine::lua::{AlgorithmHandle, LuaVec3, finite_number, script_error};
use pge_engine::{Location, Plugin};

use crate::{Forest, ForestError, ForestLod, VariantCache, VariantSharing, check_budget};
use algorithm::{ForestAlgorithm, budgeted_leaves, levels};
use options::{new_forest, scatter, terrain};

/// Adds `pge.Forest` to every session.
#[derive(Clone, Debug, Default)]
pub struct ForestPlugin {
    variant_cache: Option<VariantCache>,
    sharing: Option<VariantSharing>,
}

impl ForestPlugin {
    /// Forests keep the variants their species scripts grow in `cache` and read them back
    /// from there (`pge run --variant-cache DIR`); the output is the same.
    #[must_use]
    pub fn with_variant_cache(cache: VariantCache) -> ForestPlugin {
        ForestPlugin {
            variant_cache: Some(cache),
            sharing: None,
        }
    }

    /// Forests write only their shared variants, or refer to them instead of growing them
    /// (`pge run --variants-out DIR`, `--variants DIR`; see [`VariantSharing`]).
    #[must_use]
    pub fn sharing(mut self, sharing: VariantSharing) -> ForestPlugin {
        self.sharing = Some(sharing);
        self
    }
}

impl Plugin for ForestPlugin {
    fn name(&self) -> &str {
        "forest"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["Forest"]
    }

    fn register(&self, lua: &Lua, pge: &Table) -> mlua::Result<()> {
        if let Some(cache) = &self.variant_cache {
            lua.set_app_data(cache.clone());
        }
        if let Some(sharing) = self.sharing {
            lua.set_app_data(sharing);
        }
        pge.set("Forest", lua.create_function(new_forest)?)
    }
}

/// Where a layer's trees come from.
#[derive(Clone)]
enum Species {
    /// A script run once per variant, each in its own session.
    Path {
        /// The path shown in errors and given to the session.
        shown: String,
        /// `params` overrides as `--set` strings.
        params: Vec<(String, String)>,
    },
    /// A function `(params, seed)` called in the forest's session.
    Function { f: Function, params: Table },
}

struct Spec {
    forest: Forest,
    species: Vec<(Species, Location)>,
    location: Location,
    selected: Option<(usize, usize)>,
    /// The forest's `lod` option.
    lod: ForestLod,
}

/// A forest being described by a script (`pge.Forest{...}`); returning it runs it.
#[derive(Clone)]
pub struct LuaForest(Rc<RefCell<Spec>>);
impl UserData for LuaForest {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("terrain", |lua, me, v: Value| {
            terrain(lua, &mut me.0.borrow_mut(), v)?;
            Ok(me.clone())
        });
        m.add_method("scatter", |lua, me, v: Value| {
            scatter(lua, &mut me.0.borrow_mut(), v)?;
            Ok(me.clone())
        });
        m.add_method("height", |lua, me, (x, z): (Value, Value)| {
            let x = finite_number(lua, &x, "forest:height: x")?;
            let z = finite_number(lua, &z, "forest:height: z")?;
            Ok(me.0.borrow().forest.terrain.height(x, z))
        });
        m.add_method("normal", |lua, me, (x, z): (Value, Value)| {
            let x = finite_number(lua, &x, "forest:normal: x")?;
            let z = finite_number(lua, &z, "forest:normal: z")?;
            Ok(LuaVec3(me.0.borrow().forest.terrain.normal(x, z)))
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
            let mut spec = me.0.borrow_mut();
            let (i, j) = (i as usize, j as usize);
            spec.forest
                .tile_rect(i, j)
                .map_err(|e| mlua::Error::RuntimeError(format!("{}: {e}", spec.location)))?;
            spec.selected = Some((i, j));
            Ok(me.clone())
        });
        m.add_method("tiles", |lua, me, ()| {
            let spec = me.0.borrow();
            let Some(tiles) = spec.forest.tiles() else {
                return Err(mlua::Error::RuntimeError(format!(
                    "{}: {}",
                    spec.location,
                    ForestError::NotTiled
                )));
            };
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
            let spec = me.0.borrow();
            let layout = spec.forest.layout(spec.selected).map_err(|e| match e {
                ForestError::Script(e) => mlua::Error::RuntimeError(e.to_string()),
                other => script_error(lua, format!("forest:instances: {other}")),
            })?;
            // With a camera, each instance's leaves: the variants are grown to know theirs.
            let (leaves, lods) = if let Some(camera) = &spec.lod.camera {
                check_budget(&spec.forest, camera)
                    .map_err(|e| script_error(lua, format!("forest:instances: {e}")))?;
                let grower = ForestAlgorithm::new(me.0.clone(), lua.weak());
                let grown = grower
                    .grow(&layout, &pge_engine::lua::run_context(lua))
                    .map_err(|e| mlua::Error::RuntimeError(e.to_string()))?;
                let leaves = budgeted_leaves(&spec, &layout, &grown)
                    .map_err(|e| mlua::Error::RuntimeError(e.to_string()))?;
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
                    spec.forest.layers[i.layer as usize].name.as_str(),
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
            Ok(AlgorithmHandle::new(Box::new(ForestAlgorithm::new(
                me.0.clone(),
                lua.weak(),
            ))))
        });
    }
}
