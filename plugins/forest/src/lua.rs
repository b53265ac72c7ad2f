//! The Lua side: `pge.Forest{...}` with `:terrain`, `:scatter`, `:height`, `:normal`,
//! `:instances`, `:tiles` and `:selectTile`. A thin adapter: it reads and checks options
//! (errors at the calling line name the option and what it needs), hands plain values to
//! [`Forest`], and grows the variants of a species script in parallel, each in a session of
//! its own created by the same engine (same sandbox and limits).

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use mlua::{Function, Lua, Table, UserData, UserDataMethods, Value, WeakLua};
use pge_engine::algorithm::run;
use pge_engine::geometry::Model;
use pge_engine::lua::{
    AlgorithmHandle, Bounds, LuaVec3, Options, algorithm_from, caller_location, finite_number,
    resolve_path, script_error, to_engine_error,
};
use pge_engine::{Algorithm, Engine, Error, Location, Plugin, RunContext, SessionOptions, Step};
use rayon::prelude::*;

use pge_tree::lod::{Budget, LodOptions, MAX_SECTORS};

use crate::{
    Camera, Density, FbmOptions, Forest, ForestError, ForestLod, Grown, GrownVariant, Layer,
    Layout, Method, Raster, Terrain, VariantCache, VariantKey, VariantLod, VariantSharing,
    Variants, assemble_budgeted, check_budget, instance_leaves, layout_model, shared_layer,
    unique_seed, variant_lod, variant_seed, variants_model, with_lod,
};

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

fn describe(v: &Value) -> String {
    match v {
        Value::Integer(i) => i.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("\"{}\"", s.to_string_lossy()),
        other => other.type_name().to_string(),
    }
}

fn new_forest(lua: &Lua, v: Value) -> mlua::Result<LuaForest> {
    let o = Options::new(lua, v, "pge.Forest")?;
    let size_need = "a number > 0 or {x, z} of numbers > 0 (metres)";
    let size = match o.value("size")? {
        Value::Nil => [500.0, 500.0],
        Value::Table(t) => {
            let read = |k: i64| -> mlua::Result<f64> {
                match t.raw_get::<Value>(k)? {
                    Value::Integer(i) if i > 0 => Ok(i as f64),
                    Value::Number(n) if n.is_finite() && n > 0.0 => Ok(n),
                    other => Err(o.invalid("size", size_need, describe(&other))),
                }
            };
            [read(1)?, read(2)?]
        }
        Value::Integer(i) if i > 0 => [i as f64; 2],
        Value::Number(n) if n.is_finite() && n > 0.0 => [n; 2],
        other => return Err(o.invalid("size", size_need, describe(&other))),
    };
    let seed = match o.integer("seed", 0..=(1i64 << 53))? {
        Some(s) => s as u64,
        None => pge_engine::lua::run_context(lua).seed,
    };
    let tile = o.number("tile", Bounds::Above(0.0))?;
    let lod = forest_lod(&o)?;
    o.finish()?;
    let forest = Forest::new(size, seed, tile).map_err(|e| o.error(e))?;
    Ok(LuaForest(Rc::new(RefCell::new(Spec {
        forest,
        species: Vec::new(),
        location: caller_location(lua),
        selected: None,
        lod,
    }))))
}

/// Reads `pge.Forest{ lod = ... }`: absent or `false` for none, `true` for levels of detail
/// on every variant with the defaults, or `{sectors = n, atlas = bool, camera = {x, y, z},
/// total = T, near = d, far = d}`: levels on every variant (`sectors`, `atlas` as a tree
/// generator's `lod`) and, with `camera`, each instance's leaves for that camera (`camera`,
/// `total`, `near` and `far` go together).
fn forest_lod(o: &Options) -> mlua::Result<ForestLod> {
    let source = caller_location(o.lua()).to_string();
    let variants = LodOptions {
        source,
        ..LodOptions::default()
    };
    let t = match o.value("lod")? {
        Value::Nil | Value::Boolean(false) => return Ok(ForestLod::default()),
        Value::Boolean(true) => {
            return Ok(ForestLod {
                variants: Some(variants),
                camera: None,
            });
        }
        Value::Table(t) => t,
        other => {
            return Err(o.wrong_type(
                "lod",
                "a table {sectors, atlas, camera, total, near, far} or a boolean",
                &other,
            ));
        }
    };
    let lod = o.child("lod", t);
    let mut variants = variants;
    if let Some(n) = lod.integer("sectors", 1..=i64::from(MAX_SECTORS))? {
        variants.sectors = n as u32;
    }
    if let Some(atlas) = lod.boolean("atlas")? {
        variants.atlas = atlas;
    }
    let camera = lod.vec3("camera")?;
    let total = lod.integer("total", 0..=(1i64 << 53))?;
    let near = lod.number_f32("near", Bounds::AtLeast(0.0))?;
    let far = lod.number_f32("far", Bounds::AtLeast(0.0))?;
    lod.finish()?;
    let camera = match (camera, total, near, far) {
        (None, None, None, None) => None,
        (Some(position), Some(total), Some(near), Some(far)) => {
            if near > far {
                return Err(lod.problem(
                    "near",
                    format!("must be at most lod.far, got near = {near} and far = {far}"),
                ));
            }
            Some(Camera {
                position: position.to_array(),
                budget: Budget {
                    near,
                    far,
                    total: total as u64,
                },
            })
        }
        (camera, total, near, far) => {
            let need = "camera, total, near and far go together";
            let absent = [
                ("camera", camera.is_none()),
                ("total", total.is_none()),
                ("near", near.is_none()),
                ("far", far.is_none()),
            ];
            let key = absent
                .iter()
                .find(|(_, a)| *a)
                .map_or("camera", |(k, _)| *k);
            return Err(lod.missing(key, need));
        }
    };
    Ok(ForestLod {
        variants: Some(variants),
        camera,
    })
}

/// The path a session is given for `canonical`: relative to the working directory when it
/// lies inside it, so errors read `scripts/species/oak.lua:9:`.
fn shown_path(canonical: &Path) -> String {
    let rel = std::env::current_dir()
        .ok()
        .and_then(|d| d.canonicalize().ok())
        .and_then(|d| canonical.strip_prefix(d).ok().map(Path::to_path_buf))
        .unwrap_or_else(|| canonical.to_path_buf());
    rel.to_string_lossy().replace('\\', "/")
}

fn image(lua: &Lua, o: &Options, key: &str, relative: &str) -> mlua::Result<Arc<Raster>> {
    let path: PathBuf = resolve_path(lua, relative).map_err(|e| {
        // The sandbox's message, without the location the option's error gives again.
        let text = e.to_string();
        let reason = text.find("file '").map_or(text.as_str(), |k| &text[k..]);
        o.problem(key, format!("cannot be read: {reason}"))
    })?;
    Raster::load(&path)
        .map(Arc::new)
        .map_err(|e| o.problem(key, format!("cannot be read: {e}")))
}

fn terrain(lua: &Lua, spec: &mut Spec, v: Value) -> mlua::Result<()> {
    let o = Options::table_required(lua, v, "forest:terrain")?;
    let size = spec.forest.size;
    let resolution = o.number("resolution", Bounds::Above(0.0))?.unwrap_or(4.0);
    let height = o.number("height", Bounds::Finite)?;
    let mut fbm = FbmOptions::default();
    if let Some(h) = height {
        fbm.height = h;
    }
    if let Some(s) = o.number("scale", Bounds::Above(0.0))? {
        fbm.scale = s;
    }
    if let Some(n) = o.integer("octaves", 1..=16)? {
        fbm.octaves = n as usize;
    }
    if let Some(x) = o.number("lacunarity", Bounds::Above(0.0))? {
        fbm.lacunarity = x;
    }
    if let Some(x) = o.number("persistence", Bounds::Above(0.0))? {
        fbm.persistence = x;
    }
    let path = o.string("image")?;
    o.finish()?;
    // The noise crate's lattice index must fit an integer: the finest octave's coordinates
    // (half the world over `scale`, times lacunarity^(octaves-1)) stay within 1e12.
    let half = size[0].abs().max(size[1].abs()) / 2.0;
    let reach = half / fbm.scale * fbm.lacunarity.max(1.0).powi(fbm.octaves as i32 - 1);
    let within = reach.is_finite() && reach <= 1e12;
    if path.is_none() && !within {
        return Err(o.problem(
            "scale",
            format!(
                "is too small for this world: the finest octave samples at {reach:e} (size / 2 / \
                 scale x lacunarity^(octaves-1)), beyond 1e12; raise scale or lower lacunarity or \
                 octaves"
            ),
        ));
    }
    let terrain = match path {
        None => Terrain::fbm(size, fbm, spec.forest.seed),
        Some(path) => {
            let raster = image(lua, &o, "image", &path)?;
            Terrain::image(size, raster, height.unwrap_or(40.0))
        }
    };
    spec.forest.terrain = terrain.with_resolution(resolution);
    Ok(())
}

fn species_params(o: &Options, params: &Table) -> mlua::Result<Vec<(String, String)>> {
    let mut overrides = Vec::new();
    for pair in params.pairs::<Value, Value>() {
        let (k, v) = pair?;
        let Value::String(key) = k else {
            return Err(o.wrong_type("params", "a table of parameter overrides by name", &k));
        };
        let key = key.to_string_lossy();
        let value = match v {
            Value::Integer(i) => i.to_string(),
            Value::Number(x) => x.to_string(),
            Value::Boolean(b) => b.to_string(),
            Value::String(s) => s.to_string_lossy(),
            other => {
                return Err(o.wrong_type(
                    &format!("params.{key}"),
                    "a number, a boolean or a string",
                    &other,
                ));
            }
        };
        overrides.push((key, value));
    }
    overrides.sort();
    Ok(overrides)
}

fn scatter(lua: &Lua, spec: &mut Spec, v: Value) -> mlua::Result<()> {
    let o = Options::table_required(lua, v, "forest:scatter")?;
    let n = spec.forest.layers.len() + 1;
    let params = match o.value("params")? {
        Value::Nil => lua.create_table()?,
        Value::Table(p) => p,
        other => return Err(o.wrong_type("params", "a table of parameter overrides", &other)),
    };
    let species_need = "a script path or a function(params, seed)";
    let (species, name) = match o.value("species")? {
        Value::String(s) => {
            let canonical = resolve_path(lua, &s.to_string_lossy())?;
            let name = canonical
                .file_stem()
                .map_or_else(|| format!("layer{n}"), |s| s.to_string_lossy().to_string());
            let params = species_params(&o, &params)?;
            let shown = shown_path(&canonical);
            (Species::Path { shown, params }, name)
        }
        Value::Function(f) => (Species::Function { f, params }, format!("layer{n}")),
        Value::Nil => return Err(o.missing("species", species_need)),
        other => return Err(o.wrong_type("species", species_need, &other)),
    };
    let Some(min_distance) = o.number("minDistance", Bounds::Above(0.0))? else {
        return Err(o.missing("minDistance", "metres between trunks, a number > 0"));
    };
    let mut layer = Layer::new(name, min_distance);
    let jitter = o.number("jitter", Bounds::Between(0.0, 0.49))?;
    layer.method = match o.choice("method", &["poisson", "jittered"])? {
        Some("jittered") => Method::Jittered {
            jitter: jitter.unwrap_or(0.2),
        },
        _ => Method::Poisson,
    };
    let density_need = "a number between 0 and 1, a function(x, z) or a PNG path";
    layer.density = match o.value("density")? {
        Value::Nil => Density::Constant(1.0),
        Value::Integer(i) if (0..=1).contains(&i) => Density::Constant(i as f64),
        Value::Number(d) if (0.0..=1.0).contains(&d) => Density::Constant(d),
        v @ (Value::Integer(_) | Value::Number(_)) => {
            return Err(o.invalid("density", "a number between 0 and 1", describe(&v)));
        }
        Value::String(s) => Density::Map(image(lua, &o, "density", &s.to_string_lossy())?),
        Value::Function(f) => {
            let weak = lua.weak();
            let location = caller_location(lua);
            Density::Function(Rc::new(move |x: f64, z: f64| {
                f.call::<Value>((x, z))
                    .and_then(|v| match v {
                        Value::Integer(i) => Ok(i as f64),
                        Value::Number(n) => Ok(n),
                        other => Err(mlua::Error::RuntimeError(format!(
                            "density function: must return a number between 0 and 1, got {}",
                            other.type_name()
                        ))),
                    })
                    .map_err(|e| lua_error(&weak, &location, e))
            }))
        }
        other => return Err(o.wrong_type("density", density_need, &other)),
    };
    if let Some((a, b)) = o.range("slope", Bounds::Between(0.0, 90.0))? {
        layer.slope = [a, b];
    }
    if let Some((a, b)) = o.range("altitude", Bounds::Finite)? {
        layer.altitude = [a, b];
    }
    if let Some((a, b)) = o.range("scale", Bounds::Above(0.0))? {
        layer.scale = [a, b];
    }
    layer.variants = match o.value("variants")? {
        Value::Nil => Variants::Count(8),
        Value::String(s) if s.to_string_lossy() == "unique" => Variants::Unique,
        _ => match o.integer("variants", 1..=10_000) {
            Ok(Some(v)) => Variants::Count(v as u32),
            Ok(None) => Variants::Count(8),
            Err(_) => {
                let v = o.value("variants")?;
                return Err(o.invalid(
                    "variants",
                    "an integer between 1 and 10000 or \"unique\"",
                    describe(&v),
                ));
            }
        },
    };
    o.finish()?;
    layer.check().map_err(|e| o.error(e))?;
    spec.forest.layers.push(layer);
    spec.species.push((species, caller_location(lua)));
    Ok(())
}

fn lua_error(weak: &WeakLua, location: &Location, e: mlua::Error) -> Error {
    match weak.try_upgrade() {
        Some(lua) => to_engine_error(&lua, e),
        None => Error::script(location.clone(), e.to_string()),
    }
}

fn forest_error(location: &Location, e: ForestError) -> Error {
    match e {
        ForestError::Script(e) => e,
        other => Error::script(location.clone(), other.to_string()),
    }
}

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

/// A forest run step by step: layout, variants, assembly.
struct ForestAlgorithm {
    spec: Rc<RefCell<Spec>>,
    lua: WeakLua,
    layout: Option<Layout>,
    grown: Option<Vec<Grown>>,
    model: Option<Model>,
    /// Seconds of each step, reported as phases of the run.
    phases: Vec<(&'static str, f64)>,
}

impl ForestAlgorithm {
    /// The forest of `spec`, not yet run.
    fn new(spec: Rc<RefCell<Spec>>, lua: WeakLua) -> ForestAlgorithm {
        ForestAlgorithm {
            spec,
            lua,
            layout: None,
            grown: None,
            model: None,
            phases: Vec::new(),
        }
    }
}

/// A species script: its shown path and `params` overrides.
type ScriptSpecies = (String, Vec<(String, String)>);

/// Grows one variant of a species script in a session of its own; returns it with the
/// files the session read.
fn grow_script(
    engine: &Engine,
    shown: &str,
    params: &[(String, String)],
    seed: u64,
    ctx: &RunContext,
) -> pge_engine::Result<GrownVariant> {
    let session = engine.session(SessionOptions {
        seed,
        params: params.to_vec(),
        steps: None,
        cancel: ctx.cancel.clone(),
    })?;
    let model = session.generate(Path::new(shown), &mut |_, _| {})?.model;
    Ok((model, session.loaded_files()))
}

/// [`grow_script`] through the variant cache, when the run has one (`--variant-cache`).
fn grow_cached(
    engine: &Engine,
    cache: Option<&VariantCache>,
    (shown, params): &ScriptSpecies,
    seed: u64,
    ctx: &RunContext,
    location: &Location,
) -> pge_engine::Result<Model> {
    let grow = || grow_script(engine, shown, params, seed, ctx);
    match cache {
        None => grow().map(|(model, _)| model),
        Some(cache) => {
            let key = VariantKey {
                shown,
                params,
                seed,
                max_modules: ctx.max_modules,
            };
            cache.variant(&key, &location.to_string(), grow)
        }
    }
}

impl ForestAlgorithm {
    fn grow(&self, layout: &Layout, ctx: &RunContext) -> pge_engine::Result<Vec<Grown>> {
        let spec = self.spec.borrow();
        let seed = spec.forest.seed;
        // Layers whose variants a tile refers to rather than grows (`--variants DIR`).
        let referred = |l: usize| {
            self.sharing() == Some(VariantSharing::Refer) && shared_layer(&spec.forest, l)
        };
        // (layer, variant, seed) of every tree to grow, in a fixed order.
        let mut jobs: Vec<Vec<u64>> = Vec::new();
        for (l, layer) in spec.forest.layers.iter().enumerate() {
            jobs.push(match layer.variants {
                Variants::Count(n) => (0..n).map(|v| variant_seed(seed, l, v)).collect(),
                Variants::Unique => layout
                    .instances
                    .iter()
                    .filter(|i| i.layer as usize == l)
                    .map(|i| unique_seed(seed, i))
                    .collect(),
            });
        }
        let mut scripts: Vec<(usize, usize, u64)> = Vec::new();
        for (l, (species, _)) in spec.species.iter().enumerate() {
            if matches!(species, Species::Path { .. }) && !referred(l) {
                scripts.extend(jobs[l].iter().enumerate().map(|(v, &s)| (l, v, s)));
            }
        }
        let engine = match self.lua.try_upgrade() {
            Some(lua) => pge_engine::lua::engine(&lua),
            None => None,
        };
        let mut grown: Vec<Grown> = jobs
            .iter()
            .map(|j| Grown {
                variants: Vec::with_capacity(j.len()),
            })
            .collect();
        if !scripts.is_empty() {
            let Some(engine) = engine else {
                return Err(Error::script(
                    spec.location.clone(),
                    "pge.Forest: species scripts need a session created by an engine",
                ));
            };
            let paths: Vec<Option<ScriptSpecies>> = spec
                .species
                .iter()
                .map(|(s, _)| match s {
                    Species::Path { shown, params } => Some((shown.clone(), params.clone())),
                    Species::Function { .. } => None,
                })
                .collect();
            let ctx_send = ctx.clone();
            // Layers of a few variants shared by every tile go through the cache; "unique"
            // trees are grown where they stand.
            let cache = self.lua.try_upgrade().and_then(|lua| {
                lua.app_data_ref::<VariantCache>()
                    .map(|c| VariantCache::clone(&c))
            });
            let cached: Vec<Option<&VariantCache>> = spec
                .forest
                .layers
                .iter()
                .map(|layer| match layer.variants {
                    Variants::Count(_) => cache.as_ref(),
                    Variants::Unique => None,
                })
                .collect();
            let locations: Vec<Location> = spec.species.iter().map(|(_, l)| l.clone()).collect();
            let results: Vec<pge_engine::Result<Model>> = scripts
                .par_iter()
                .map(|&(l, _, s)| match &paths[l] {
                    Some(species) => {
                        grow_cached(&engine, cached[l], species, s, &ctx_send, &locations[l])
                    }
                    None => Err(Error::Export("not a script species".into())),
                })
                .collect();
            for (&(l, _, _), r) in scripts.iter().zip(results) {
                let model = r.map_err(|e| {
                    let shown = match &spec.species[l].0 {
                        Species::Path { shown, .. } => shown.as_str(),
                        Species::Function { .. } => "",
                    };
                    Error::script(
                        spec.species[l].1.clone(),
                        format!("forest:scatter: species '{shown}' failed: {e}"),
                    )
                })?;
                grown[l].variants.push(model);
            }
        }
        for (l, (species, location)) in spec.species.iter().enumerate() {
            let Species::Function { f, params } = species else {
                continue;
            };
            if referred(l) {
                continue;
            }
            let Some(lua) = self.lua.try_upgrade() else {
                return Err(Error::script(location.clone(), "the Lua state is gone"));
            };
            for &s in &jobs[l] {
                ctx.check_deadline(location)?;
                let value: Value = f
                    .call((params.clone(), s))
                    .map_err(|e| to_engine_error(&lua, e))?;
                let mut algorithm = algorithm_from(&lua, value, location)?;
                let inner = RunContext {
                    seed: s,
                    steps: None,
                    ..ctx.clone()
                };
                grown[l]
                    .variants
                    .push(run(&mut *algorithm, &inner, &mut |_| {})?);
            }
        }
        for (l, g) in grown.iter_mut().enumerate() {
            if referred(l) {
                g.variants = vec![Model::new(); jobs[l].len()];
            }
        }
        if let Some(options) = &spec.lod.variants {
            give_levels(&spec, &mut grown, options)?;
        }
        Ok(grown)
    }

    /// The run's [`VariantSharing`], if any.
    fn sharing(&self) -> Option<VariantSharing> {
        let lua = self.lua.try_upgrade()?;
        lua.app_data_ref::<VariantSharing>().map(|s| *s)
    }
}

/// The levels of every grown variant, by layer and variant.
fn levels(grown: &[Grown]) -> Vec<Vec<Option<VariantLod>>> {
    grown
        .iter()
        .map(|g| g.variants.iter().map(variant_lod).collect())
        .collect()
}

/// How many leaves each instance of `layout` draws for the forest's camera, `None` without
/// one; errors at the `pge.Forest` line.
fn budgeted_leaves(
    spec: &Spec,
    layout: &Layout,
    grown: &[Grown],
) -> pge_engine::Result<Option<Vec<Option<u32>>>> {
    let Some(camera) = &spec.lod.camera else {
        return Ok(None);
    };
    instance_leaves(&spec.forest, layout, spec.selected, &levels(grown), camera)
        .map(Some)
        .map_err(|e| forest_error(&spec.location, e))
}

/// The forest's model: the layout's instances of the grown variants, with each instance's
/// leaves when the forest has a camera.
fn assembled(spec: &Spec, layout: &Layout, grown: &[Grown]) -> pge_engine::Result<Model> {
    let leaves = budgeted_leaves(spec, layout, grown)?;
    Ok(assemble_budgeted(
        &spec.forest,
        layout,
        grown,
        spec.selected,
        leaves.as_deref(),
    ))
}

/// Gives every grown variant the forest's levels of detail ([`with_lod`]), in parallel; the
/// first failure in (layer, variant) order is the error, at the `pge.Forest` line.
fn give_levels(spec: &Spec, grown: &mut [Grown], options: &LodOptions) -> pge_engine::Result<()> {
    let mut models: Vec<(usize, usize, &mut Model)> = Vec::new();
    for (l, g) in grown.iter_mut().enumerate() {
        for (v, model) in g.variants.iter_mut().enumerate() {
            models.push((l, v, model));
        }
    }
    let names: Vec<&str> = spec.forest.layers.iter().map(|x| x.name.as_str()).collect();
    let results: Vec<Result<(), String>> = models
        .par_iter_mut()
        .map(|(l, v, model)| {
            let given = with_lod(model, options).map_err(|e| {
                let name = names.get(*l).copied().unwrap_or("");
                format!(
                    "pge.Forest: lod: variant {v} of layer {} ({name}): {e}",
                    *l + 1
                )
            })?;
            **model = given;
            Ok(())
        })
        .collect();
    match results.into_iter().find_map(Result::err) {
        Some(message) => Err(Error::script(spec.location.clone(), message)),
        None => Ok(()),
    }
}

impl Algorithm for ForestAlgorithm {
    fn name(&self) -> &str {
        "pge.Forest"
    }

    fn init(&mut self, _: &RunContext) -> pge_engine::Result<()> {
        self.layout = None;
        self.grown = None;
        self.model = None;
        Ok(())
    }

    fn step(&mut self, ctx: &RunContext) -> pge_engine::Result<Step> {
        let t0 = std::time::Instant::now();
        let (name, step) = self.step_timed(ctx)?;
        self.phases.push((name, t0.elapsed().as_secs_f64()));
        Ok(step)
    }

    fn finish(&mut self, _: &RunContext) -> pge_engine::Result<Model> {
        let spec = self.spec.borrow();
        let mut model = match (&self.model, &self.layout, &self.grown) {
            (Some(model), _, _) => model.clone(),
            (None, _, Some(grown)) if self.sharing() == Some(VariantSharing::Write) => {
                variants_model(&spec.forest, grown)
            }
            (None, Some(layout), Some(grown)) => assembled(&spec, layout, grown)?,
            (None, Some(layout), None) => layout_model(&spec.forest, layout, spec.selected),
            _ => layout_model(&spec.forest, &Layout::default(), spec.selected),
        };
        for (name, seconds) in &self.phases {
            model.stats.add_phase(name, *seconds);
        }
        Ok(model)
    }

    fn planned_steps(&self) -> Option<u32> {
        Some(3)
    }
}

impl ForestAlgorithm {
    /// One step: layout, then variants, then assembly; returns the step's name.
    fn step_timed(&mut self, ctx: &RunContext) -> pge_engine::Result<(&'static str, Step)> {
        if self.layout.is_none() && self.sharing() == Some(VariantSharing::Write) {
            // Writing the shared variants: no trees to place.
            self.layout = Some(Layout::default());
            return Ok(("layout", Step::Continue));
        }
        if self.layout.is_none() {
            let spec = self.spec.borrow();
            if let Some(camera) = &spec.lod.camera {
                check_budget(&spec.forest, camera).map_err(|e| {
                    Error::script(spec.location.clone(), format!("pge.Forest: {e}"))
                })?;
                if self.sharing() == Some(VariantSharing::Refer) {
                    return Err(Error::script(
                        spec.location.clone(),
                        "pge.Forest: lod.camera needs the variants' leaves, which a tile \
                         referring to shared variants (--variants) does not grow: write \
                         standalone tiles",
                    ));
                }
            }
            let mut layout = spec
                .forest
                .layout(spec.selected)
                .map_err(|e| forest_error(&spec.location, e))?;
            // Warnings point at the scatter call of the layer that fits no tree.
            let empty = layout.counts.iter().enumerate().filter(|(_, c)| **c == 0);
            let located: Vec<String> = empty
                .zip(&layout.warnings)
                .map(|((l, _), w)| format!("{}: warning: forest:scatter: {w}", spec.species[l].1))
                .collect();
            layout.warnings = located;
            drop(spec);
            self.layout = Some(layout);
            return Ok(("layout", Step::Continue));
        }
        if self.grown.is_none() {
            let grown = match &self.layout {
                Some(layout) => self.grow(layout, ctx)?,
                None => self.grow(&Layout::default(), ctx)?,
            };
            self.grown = Some(grown);
            return Ok(("variants", Step::Continue));
        }
        if self.model.is_none() {
            let spec = self.spec.borrow();
            if let (Some(layout), Some(grown)) = (&self.layout, &self.grown) {
                self.model = Some(if self.sharing() == Some(VariantSharing::Write) {
                    variants_model(&spec.forest, grown)
                } else {
                    assembled(&spec, layout, grown)?
                });
            }
        }
        Ok(("assembly", Step::Done))
    }
}
