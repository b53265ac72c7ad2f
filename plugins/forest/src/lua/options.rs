//! Reading the options of `pge.Forest{...}`, `forest:terrain{...}` and
//! `forest:scatter{...}` into the plain values of [`Forest`] and its [`Layer`]s; errors at
//! the calling line name the option and what it needs.

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

use mlua::{Function, Lua, Table, Value};
use pge_engine::lua::{
    Bounds, Options, caller_location, read_file, resolve_path, shown_path, to_engine_error,
};
use pge_engine::{Error, Location};

use pge_lod::{Budget, LodOptions, MAX_SECTORS};

use super::grower::grow_with_function;
use super::{LuaForest, Setup};
use crate::{
    Camera, Density, FbmOptions, ForestLod, ForestSpec, Layer, Method, Raster, ScriptSpecies,
    Species, Terrain, Variants,
};

fn describe(v: &Value) -> String {
    match v {
        Value::Integer(i) => i.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("\"{}\"", s.to_string_lossy()),
        other => other.type_name().to_string(),
    }
}

pub(super) fn new_forest(lua: &Lua, v: Value, setup: Rc<Setup>) -> mlua::Result<LuaForest> {
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
    let mut spec = ForestSpec::new(size, seed, tile)
        .map_err(|e| o.error(e))?
        .described_at(caller_location(lua));
    spec.lod = lod;
    Ok(LuaForest {
        spec: Rc::new(RefCell::new(spec)),
        setup,
    })
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

fn image(lua: &Lua, o: &Options, key: &str, relative: &str) -> mlua::Result<Arc<Raster>> {
    let path: PathBuf = resolve_path(lua, relative).map_err(|e| {
        // The sandbox's message, without the location the option's error gives again.
        let text = e.to_string();
        let reason = text.find("file '").map_or(text.as_str(), |k| &text[k..]);
        o.problem(key, format!("cannot be read: {reason}"))
    })?;
    let bytes =
        read_file(lua, &path).map_err(|e| o.problem(key, format!("cannot be read: {e}")))?;
    Raster::decode(&path.display().to_string(), &bytes)
        .map(Arc::new)
        .map_err(|e| o.problem(key, format!("cannot be read: {e}")))
}

pub(super) fn terrain(lua: &Lua, spec: &mut ForestSpec, v: Value) -> mlua::Result<()> {
    let o = Options::table_required(lua, v, "forest:terrain")?;
    let size = spec.forest().size;
    let resolution = o.number("resolution", Bounds::Above(0.0))?.unwrap_or(4.0);
    let height = o.number("height", Bounds::Finite)?;
    let mut fbm = FbmOptions::default();
    if let Some(h) = height {
        fbm.height = h;
    }
    let scale = o.number("scale", Bounds::Above(0.0))?;
    let octaves = o.integer("octaves", 1..=16)?;
    let lacunarity = o.number("lacunarity", Bounds::Above(0.0))?;
    let persistence = o.number("persistence", Bounds::Above(0.0))?;
    let path = o.string("image")?;
    // The noise's options shape generated terrain only: with an image they would do nothing.
    if path.is_some() {
        let noise = [
            ("scale", scale.is_some()),
            ("octaves", octaves.is_some()),
            ("lacunarity", lacunarity.is_some()),
            ("persistence", persistence.is_some()),
        ];
        if let Some((name, _)) = noise.iter().find(|(_, given)| *given) {
            return Err(o.problem(
                name,
                "shapes the generated terrain and does nothing with image (give one or the \
                 other)",
            ));
        }
    }
    if let Some(s) = scale {
        fbm.scale = s;
    }
    if let Some(n) = octaves {
        fbm.octaves = n as usize;
    }
    if let Some(x) = lacunarity {
        fbm.lacunarity = x;
    }
    if let Some(x) = persistence {
        fbm.persistence = x;
    }
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
        None => Terrain::fbm(size, fbm, spec.forest().seed),
        Some(path) => {
            let raster = image(lua, &o, "image", &path)?;
            Terrain::image(size, raster, height.unwrap_or(40.0))
        }
    };
    spec.set_terrain(terrain.with_resolution(resolution));
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

pub(super) fn scatter(lua: &Lua, spec: &mut ForestSpec, v: Value) -> mlua::Result<()> {
    let o = Options::table_required(lua, v, "forest:scatter")?;
    let n = spec.forest().layers.len() + 1;
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
            // Relative to the working folder, so errors read `scripts/species/oak.lua:9:`.
            let path = shown_path(lua, &canonical);
            (Species::Script(ScriptSpecies { path, params }), name)
        }
        Value::Function(f) => {
            let location = caller_location(lua);
            let grow = move |_seed: u64, ctx: &pge_engine::RunContext| {
                grow_with_function(&f, &params, ctx, &location)
            };
            (Species::Function(Rc::new(grow)), format!("layer{n}"))
        }
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
        _ if jitter.is_some() => {
            return Err(o.problem(
                "jitter",
                "is for method = \"jittered\" only (Poisson disc sampling has no jitter)",
            ));
        }
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
            // Every error of the function is placed: its own line when Lua knows it, else
            // the `forest:scatter` line that gave the function.
            let location = caller_location(lua);
            Density::Function(Rc::new(move |x: f64, z: f64| {
                let wrong = |got: String| {
                    Error::script(
                        location.clone(),
                        format!(
                            "forest:scatter: density: the function returned {got} at ({x:.2}, \
                             {z:.2}); it must return a number between 0 and 1"
                        ),
                    )
                };
                let d = match f.call::<Value>((x, z)) {
                    Ok(Value::Integer(i)) => i as f64,
                    Ok(Value::Number(n)) => n,
                    Ok(other) => return Err(wrong(format!("a {}", other.type_name()))),
                    Err(e) => return Err(lua_error(&f, &location, e)),
                };
                if !(0.0..=1.0).contains(&d) {
                    return Err(wrong(d.to_string()));
                }
                Ok(d)
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
    spec.add_layer_at(layer, species, caller_location(lua))
        .map_err(|e| o.error(e))?;
    Ok(())
}

/// The error of a call of the script's function `f`, with the script's file and line.
fn lua_error(f: &Function, location: &Location, e: mlua::Error) -> Error {
    match f.weak_lua().try_upgrade() {
        Some(lua) => match to_engine_error(&lua, e) {
            // Lua could not say where (an error value that is not a message): the
            // `forest:scatter` line is.
            e if e.location().is_some_and(|l| l.file == "?") => e.at(location.clone()),
            e => e,
        },
        None => Error::script(location.clone(), e.to_string()),
    }
}
