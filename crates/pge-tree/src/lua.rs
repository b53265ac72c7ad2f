//! The Lua side of tree options, shared by every generator's constructor
//! (`pge.SpaceColonization{...}`, `pge.turtle{...}`, `pge.Growth{...}`), read with the
//! engine's [`Options`] reader:
//!
//! ```lua
//! {
//!   radius = { tip = 0.02, exponent = 2.3 },   -- shorthand for mesh.tipRadius / mesh.exponent
//!   smoothing = 0.5,                           -- shorthand for mesh.smoothing
//!   sides = 8,                                 -- shorthand for mesh.sides
//!   mesh = { sides = 8, caps = true, exponent = 2.3, tipRadius = 0.02, mergeStraight = 5,
//!            smoothing = 0, radii = "pipe", color = "#6b5444", texture = "bark.png",
//!            bark = "furrowed",            -- or { style = "plated", depth = 1.5 }
//!            textureSize = 512, textureFormat = "jpeg", textureScale = 0.6,
//!            light = {0.45, 0.8, 0.35},
//!            flare = { roots = 5, spread = 1, height = 1 } },   -- or flare = true
//!   leaves = { perTip = {3, 6}, size = 0.25, width = 1, colors = {"#2f6b1f", "#7da83a"}, maxDepth = 2,
//!              texture = "leaf.png", shape = "lobed", textureSize = 512,
//!              backColor = "#c8dc64", translucency = 0.3, perCard = 1,
//!              along = { orders = 2, spacing = 0.3 } },
//!   lod = { sectors = 1, atlas = false },      -- foliage levels of detail (pge_lod)
//! }
//! ```
//! Keys inside `mesh` take precedence over the shorthands. Unknown keys inside `mesh`,
//! `leaves` and `radius` are errors; the generator refuses unknown top-level keys when it
//! finishes reading its own.

use std::path::PathBuf;

use mlua::{Lua, Value};
use pge_engine::lua::{
    Bounds, Options, caller_location, error_message, read_file, resolve_path, script_error,
};

use crate::TreeError;
use crate::options::{
    Along, Flare, LeafOptions, MAX_PER_CARD, MeshOptions, RadiiMode, TextureSource, TreeOptions,
};
use crate::textures::{BarkStyle, LeafShape, TextureFormat, decode_png};

/// [`tree_options`] for a generator that computes its own radii (growth, conifer): the
/// mesher keeps them ([`RadiiMode::Keep`](crate::RadiiMode::Keep)) unless the script's
/// `mesh.radii` asks for another mode.
pub fn tree_options_keeping_radii(o: &Options) -> mlua::Result<TreeOptions> {
    let radii_given = match o.value("mesh")? {
        Value::Table(m) => !m.get::<Value>("radii")?.is_nil(),
        _ => false,
    };
    let mut tree = tree_options(o)?;
    if !radii_given {
        tree.mesh.radii = crate::RadiiMode::Keep;
    }
    Ok(tree)
}

/// Reads [`TreeOptions`] from a generator's options (the keys in the module docs), then
/// resolves texture paths next to the calling script (recorded for live reload) and loads
/// them. Every problem is a `FILE:LINE: WHAT: option ...` error at the calling line.
pub fn tree_options(o: &Options) -> mlua::Result<TreeOptions> {
    let mut mesh = MeshOptions::default();
    match o.value("radius")? {
        Value::Nil => {}
        Value::Table(t) => {
            let r = o.child("radius", t);
            if let Some(v) = r.number_f32("tip", Bounds::Above(0.0))? {
                mesh.tip_radius = v;
            }
            if let Some(v) = r.number_f32("exponent", Bounds::Between(1.0, 4.0))? {
                mesh.exponent = v;
            }
            r.finish()?;
        }
        Value::Integer(_) | Value::Number(_) => {
            if let Some(v) = o.number_f32("radius", Bounds::Above(0.0))? {
                mesh.tip_radius = v;
            }
        }
        other => {
            return Err(o.wrong_type("radius", "a table {tip = r, exponent = n}", &other));
        }
    }
    if let Some(v) = o.number_f32("smoothing", Bounds::Between(0.0, 1.0))? {
        mesh.smoothing = v;
    }
    if let Some(v) = o.integer("sides", 3..=64)? {
        mesh.sides = v as u32;
    }
    match o.value("mesh")? {
        Value::Nil => {}
        Value::Table(t) => read_mesh(&o.child("mesh", t), &mut mesh)?,
        other => return Err(o.wrong_type("mesh", "a table of mesh options", &other)),
    }
    let leaves = match o.value("leaves")? {
        Value::Nil | Value::Boolean(false) => None,
        Value::Boolean(true) => Some(LeafOptions::default()),
        Value::Table(t) => Some(leaf_options(&o.child("leaves", t))?),
        other => {
            return Err(o.wrong_type("leaves", "a table of leaf options or false", &other));
        }
    };
    let lod = pge_lod::lua::lod_options(o)?;
    let mut options = TreeOptions { mesh, leaves, lod };
    load_texture(o, "mesh.texture", "bark", &mut options.mesh.texture)?;
    if let Some(leaves) = &mut options.leaves {
        load_texture(o, "leaves.texture", "leaf", &mut leaves.texture)?;
    }
    Ok(options)
}

/// Reads a `mesh = {...}` table (its [`Options`], from [`Options::child`]) into `mesh`:
/// `sides`, `caps`, `exponent`, `tipRadius`, `mergeStraight` (degrees, or a boolean: true is
/// 5 degrees), `smoothing`, `radii` (`"pipe"` or `"keep"`), `color`, `texture` (a PNG path,
/// not loaded yet: see [`load_texture`]), `bark` (a style name or `{style, depth}`),
/// `textureSize`, `textureFormat` (`"jpeg"` or `"png"`), `textureScale`, `light` and `flare`
/// (`true` or `{roots, spread, height}`).
/// Absent keys keep what `mesh` holds.
pub fn read_mesh(o: &Options, mesh: &mut MeshOptions) -> mlua::Result<()> {
    if let Some(v) = o.integer("sides", 3..=64)? {
        mesh.sides = v as u32;
    }
    if let Some(v) = o.boolean("caps")? {
        mesh.caps = v;
    }
    if let Some(v) = o.number_f32("exponent", Bounds::Between(1.0, 4.0))? {
        mesh.exponent = v;
    }
    if let Some(v) = o.number_f32("tipRadius", Bounds::Above(0.0))? {
        mesh.tip_radius = v;
    }
    match o.value("mergeStraight")? {
        Value::Nil => {}
        Value::Boolean(b) => mesh.merge_straight = b.then_some(5.0),
        _ => mesh.merge_straight = o.number_f32("mergeStraight", Bounds::Between(0.0, 45.0))?,
    }
    if let Some(v) = o.number_f32("smoothing", Bounds::Between(0.0, 1.0))? {
        mesh.smoothing = v;
    }
    if let Some(radii) = o.choice("radii", &["pipe", "keep"])? {
        mesh.radii = if radii == "keep" {
            RadiiMode::Keep
        } else {
            RadiiMode::Pipe
        };
    }
    if let Some(c) = o.color("color")? {
        mesh.color = c;
    }
    if let Some(path) = o.string("texture")? {
        mesh.texture = TextureSource::File(PathBuf::from(path));
    }
    match o.value("bark")? {
        Value::Nil => {}
        Value::Table(t) => {
            let b = o.child("bark", t);
            if let Some(style) = b.choice("style", &BarkStyle::NAMES)? {
                mesh.bark = BarkStyle::from_name(style).unwrap_or_default();
            }
            if let Some(v) = b.number_f32("depth", Bounds::Between(0.0, 4.0))? {
                mesh.bark_depth = v;
            }
            b.finish()?;
        }
        _ => {
            if let Some(style) = o.choice("bark", &BarkStyle::NAMES)? {
                mesh.bark = BarkStyle::from_name(style).unwrap_or_default();
            }
        }
    }
    if let Some(v) = o.integer("textureSize", 16..=2048)? {
        mesh.texture_size = v as u32;
    }
    if let Some(format) = o.choice("textureFormat", &TextureFormat::NAMES)? {
        mesh.texture_format = TextureFormat::from_name(format).unwrap_or_default();
    }
    if let Some(v) = o.number_f32("textureScale", Bounds::Above(0.0))? {
        mesh.texture_scale = v;
    }
    if let Some(v) = o.vec3("light")? {
        if v.length_squared() == 0.0 {
            return Err(o.problem("light", "must be a non-zero direction {x, y, z}"));
        }
        mesh.light = v;
    }
    match o.value("flare")? {
        Value::Nil | Value::Boolean(false) => {}
        Value::Boolean(true) => mesh.flare = Some(Flare::default()),
        Value::Table(t) => {
            let f = o.child("flare", t);
            let mut flare = Flare::default();
            if let Some(v) = f.integer("roots", 2..=16)? {
                flare.roots = v as u32;
            }
            if let Some(v) = f.number_f32("spread", Bounds::Between(0.0, 4.0))? {
                flare.spread = v;
            }
            if let Some(v) = f.number_f32("height", Bounds::Above(0.0))? {
                flare.height = v;
            }
            f.finish()?;
            mesh.flare = Some(flare);
        }
        other => {
            return Err(o.wrong_type("flare", "true or a table {roots, spread, height}", &other));
        }
    }
    o.finish()
}

/// Reads a `leaves = {...}` table (its [`Options`], from [`Options::child`]): `perTip =
/// {min, max}` (or one number), `size`, `width`, `colors = {"#rrggbb", "#rrggbb"}` (or one
/// colour), `maxDepth`, `texture` (a PNG path, not loaded yet: see [`load_texture`]),
/// `shape` (`"ovate"`, `"lobed"`, `"lanceolate"`, `"palmate"` or `"needles"`), `textureSize`,
/// `backColor` (`"#rrggbb"`), `translucency` (0..=1), `perCard` (leaves a card draws,
/// 1..=12) and `along` (`true` or `{orders = 1..=8, spacing = 0.02..=100}`: cards along the
/// last branch orders). The options remember the calling line for warnings.
pub fn leaf_options(o: &Options) -> mlua::Result<LeafOptions> {
    let mut leaves = LeafOptions::default();
    if let Some((min, max)) = o.integer_range("perTip", 0..=1000)? {
        leaves.per_tip = (min as u32, max as u32);
    }
    if let Some(v) = o.number_f32("size", Bounds::Above(0.0))? {
        leaves.size = v;
    }
    if let Some(v) = o.number_f32("width", Bounds::AboveAtMost(0.0, 4.0))? {
        leaves.width = v;
    }
    match o.value("colors")? {
        Value::Nil => {}
        Value::String(_) => {
            if let Some(c) = o.color("colors")? {
                leaves.colors = [c, c];
            }
        }
        Value::Table(list) => {
            let (a, b): (Value, Value) = (list.raw_get(1)?, list.raw_get(2)?);
            let color = |key: &str, v: &Value| -> mlua::Result<[f32; 4]> {
                let at = format!("colors[{key}]");
                match v {
                    Value::String(s) => {
                        let text = s.to_string_lossy();
                        pge_engine::geometry::Material::from_hex("", &text)
                            .map(|m| m.base_color)
                            .map_err(|_| {
                                o.invalid(&at, "a colour \"#rrggbb\"", format!("\"{text}\""))
                            })
                    }
                    other => Err(o.wrong_type(&at, "a colour \"#rrggbb\"", other)),
                }
            };
            leaves.colors = match (&a, &b) {
                (Value::Nil, _) => {
                    return Err(o.problem("colors", "must be {\"#rrggbb\", \"#rrggbb\"}"));
                }
                (a, Value::Nil) => {
                    let c = color("1", a)?;
                    [c, c]
                }
                (a, b) => [color("1", a)?, color("2", b)?],
            };
        }
        other => return Err(o.wrong_type("colors", "{\"#rrggbb\", \"#rrggbb\"}", &other)),
    }
    if let Some(v) = o.integer("maxDepth", 0..=1000)? {
        leaves.max_depth = v as u32;
    }
    if let Some(path) = o.string("texture")? {
        leaves.texture = TextureSource::File(PathBuf::from(path));
    }
    if let Some(shape) = o.choice("shape", &LeafShape::NAMES)? {
        leaves.shape = LeafShape::from_name(shape).unwrap_or_default();
    }
    if let Some(v) = o.integer("textureSize", 16..=2048)? {
        leaves.texture_size = v as u32;
    }
    if let Some(c) = o.color("backColor")? {
        leaves.back_color = c;
    }
    if let Some(v) = o.number_f32("translucency", Bounds::Between(0.0, 1.0))? {
        leaves.translucency = v;
    }
    if let Some(v) = o.integer("perCard", 1..=i64::from(MAX_PER_CARD))? {
        leaves.per_card = v as u32;
    }
    match o.value("along")? {
        Value::Nil | Value::Boolean(false) => {}
        Value::Boolean(true) => leaves.along = Some(Along::default()),
        Value::Table(t) => {
            let a = o.child("along", t);
            let mut along = Along::default();
            if let Some(v) = a.integer("orders", 1..=8)? {
                along.orders = v as u32;
            }
            if let Some(v) = a.number_f32("spacing", Bounds::Between(0.02, 100.0))? {
                along.spacing = v;
            }
            a.finish()?;
            leaves.along = Some(along);
        }
        other => {
            return Err(o.wrong_type("along", "true or a table {orders, spacing}", &other));
        }
    }
    leaves.source = caller_location(o.lua()).to_string();
    o.finish()?;
    Ok(leaves)
}

/// Reads a texture given as a file path, relative to the calling script and inside the
/// folders scripts may read (recorded for live reload), and replaces the path by the image.
/// `key` names the option in errors (`mesh.texture`); `name` names the texture in the glb.
pub fn load_texture(
    o: &Options,
    key: &str,
    name: &str,
    source: &mut TextureSource,
) -> mlua::Result<()> {
    load_texture_for(o.lua(), o.what(), key, name, source)
}

/// [`load_texture`] for a constructor `what` without an [`Options`] at hand.
pub fn load_texture_for(
    lua: &Lua,
    what: &str,
    key: &str,
    name: &str,
    source: &mut TextureSource,
) -> mlua::Result<()> {
    if let TextureSource::File(path) = source {
        let shown = path.to_string_lossy().into_owned();
        let file = resolve_path(lua, &shown)
            .map_err(|e| script_error(lua, format!("{what}: {key}: {}", error_message(lua, &e))))?;
        let texture = read_file(lua, &file)
            .map_err(|e| TreeError::Texture {
                path: file.clone(),
                message: e.to_string(),
            })
            .and_then(|bytes| decode_png(&file, &bytes, name))
            .map_err(|e| script_error(lua, format!("{what}: {key}: cannot read '{shown}': {e}")))?;
        *source = TextureSource::Image(texture);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mlua::Table;
    use pge_engine::{Engine, Session, SessionOptions};
    use std::cell::RefCell;
    use std::rc::Rc;

    fn session() -> Session {
        let engine = Engine::builder().build().expect("engine");
        engine.session(SessionOptions::default()).expect("session")
    }

    /// Reads the tree options of `src` (a Lua table expression) as generator `tree` would,
    /// called from Lua so that errors are located.
    fn parse(src: &str) -> Result<TreeOptions, String> {
        let s = session();
        let read = Rc::new(RefCell::new(None));
        let out = read.clone();
        let f = s
            .lua()
            .create_function(move |lua, t: Table| {
                *out.borrow_mut() = Some(tree_options(&Options::from_table(lua, t, "tree"))?);
                Ok(())
            })
            .expect("function");
        s.lua().globals().set("read", f).expect("global");
        s.eval::<()>(&format!("read({src})"))
            .map_err(|e| e.to_string())?;
        Ok(read.borrow_mut().take().expect("read"))
    }

    fn error(src: &str) -> String {
        let e = parse(src).expect_err(src);
        e.strip_prefix("eval:1: tree: ")
            .unwrap_or_else(|| panic!("located: {e}"))
            .to_string()
    }

    #[test]
    fn defaults_when_empty() {
        let o = parse("{}").expect("ok");
        assert_eq!(o, TreeOptions::default());
    }

    #[test]
    fn reads_every_option_and_mesh_wins_over_shorthands() {
        let o = parse(
            r##"{ radius = {tip = 0.05, exponent = 2.5}, smoothing = 0.5, sides = 6,
                mesh = { sides = 12, caps = false, mergeStraight = 3, radii = "keep",
                         color = "#ffffff" },
                leaves = { perTip = {1, 4}, size = 0.3, width = 0.25, colors = {"#000000", "#ffffff"},
                           maxDepth = 3 } }"##,
        )
        .expect("ok");
        assert_eq!(o.mesh.tip_radius, 0.05);
        assert_eq!(o.mesh.exponent, 2.5);
        assert_eq!(o.mesh.smoothing, 0.5);
        assert_eq!(o.mesh.sides, 12);
        assert!(!o.mesh.caps);
        assert_eq!(o.mesh.merge_straight, Some(3.0));
        assert_eq!(o.mesh.radii, RadiiMode::Keep);
        assert_eq!(o.mesh.color, [1.0; 4]);
        let l = o.leaves.expect("leaves");
        assert_eq!(l.per_tip, (1, 4));
        assert_eq!(l.size, 0.3);
        assert_eq!(l.width, 0.25);
        assert_eq!(l.colors, [[0.0, 0.0, 0.0, 1.0], [1.0; 4]]);
        assert_eq!(l.max_depth, 3);
    }

    #[test]
    fn errors_name_the_option_and_its_range() {
        let cases = [
            (
                "{ mesh = { sides = 2 } }",
                "mesh.sides must be an integer between 3 and 64, got 2",
            ),
            (
                "{ sides = 2.5 }",
                "sides must be an integer between 3 and 64, got 2.5",
            ),
            (
                "{ radius = { tip = -1 } }",
                "radius.tip must be a number > 0, got -1",
            ),
            (
                "{ radius = { tip = 0/0 } }",
                "radius.tip must be a number > 0, got NaN",
            ),
            (
                "{ mesh = { exponent = 9 } }",
                "mesh.exponent must be a number between 1 and 4, got 9",
            ),
            (
                "{ smoothing = 'x' }",
                "smoothing must be a number between 0 and 1, got string",
            ),
            (
                "{ mesh = { radii = 'x' } }",
                "mesh.radii must be \"pipe\" or \"keep\", got \"x\"",
            ),
            (
                "{ leaves = { perTip = {5, 2} } }",
                "leaves.perTip must have min <= max, got {5, 2}",
            ),
            (
                "{ leaves = { colors = {'red'} } }",
                "leaves.colors[1] must be a colour \"#rrggbb\", got \"red\"",
            ),
            (
                "{ leaves = { maxDepth = -1 } }",
                "leaves.maxDepth must be an integer between 0 and 1000, got -1",
            ),
            (
                "{ leaves = 3 }",
                "leaves must be a table of leaf options or false, got integer",
            ),
            (
                "{ mesh = { side = 3 } }",
                "unknown option 'mesh.side': 'mesh.side' is not an option (known: sides, caps, exponent, tipRadius, \
                 mergeStraight, smoothing, radii, color, texture, bark, textureSize, textureFormat, textureScale, light, flare)",
            ),
            (
                "{ mesh = { bark = 'rough' } }",
                "mesh.bark must be \"furrowed\", \"plated\", \"smooth\", \"fibrous\" or \"scaly\", got \"rough\"",
            ),
            (
                "{ mesh = { textureSize = 4096 } }",
                "mesh.textureSize must be an integer between 16 and 2048, got 4096",
            ),
            (
                "{ mesh = { flare = { roots = 1 } } }",
                "mesh.flare.roots must be an integer between 2 and 16, got 1",
            ),
            (
                "{ leaves = { shape = 'round' } }",
                "leaves.shape must be \"ovate\", \"lobed\", \"lanceolate\", \"palmate\" or \"needles\", got \"round\"",
            ),
            (
                "{ leaves = { translucency = 1.5 } }",
                "leaves.translucency must be a number between 0 and 1, got 1.5",
            ),
            (
                "{ leaves = { perCard = 0 } }",
                "leaves.perCard must be an integer between 1 and 12, got 0",
            ),
            (
                "{ leaves = { along = { spacing = 0 } } }",
                "leaves.along.spacing must be a number between 0.02 and 100, got 0",
            ),
            (
                "{ leaves = { along = 3 } }",
                "leaves.along must be true or a table {orders, spacing}, got integer",
            ),
        ];
        for (src, want) in cases {
            assert_eq!(error(src), want, "{src}");
        }
    }

    #[test]
    fn bark_leaf_shape_and_flare_options() {
        let o = parse(
            "{ mesh = { bark = { style = 'plated', depth = 2 }, textureSize = 1024, textureScale = 0.4, \
               textureFormat = 'png', light = {0, 1, 0}, flare = { roots = 6 } }, leaves = { shape = 'palmate', textureSize = 256, \
               backColor = '#ffffff', translucency = 0.5 } }",
        )
        .expect("ok");
        assert_eq!(o.mesh.bark, BarkStyle::Plated);
        assert_eq!(o.mesh.bark_depth, 2.0);
        assert_eq!(o.mesh.texture_size, 1024);
        assert_eq!(o.mesh.texture_scale, 0.4);
        assert_eq!(o.mesh.texture_format, TextureFormat::Png);
        assert_eq!(
            parse("{}").expect("ok").mesh.texture_format,
            TextureFormat::Jpeg
        );
        assert_eq!(
            parse("{ mesh = { bark = 'scaly' } }")
                .expect("ok")
                .mesh
                .bark,
            BarkStyle::Scaly
        );
        assert_eq!(o.mesh.light, glam::Vec3::Y);
        assert_eq!(
            o.mesh.flare,
            Some(Flare {
                roots: 6,
                ..Flare::default()
            })
        );
        let l = o.leaves.expect("leaves");
        assert_eq!((l.shape, l.texture_size), (LeafShape::Palmate, 256));
        assert_eq!((l.per_card, l.along), (1, None));
        assert_eq!((l.back_color, l.translucency), ([1.0; 4], 0.5));
        assert!(
            error("{ leaves = { backColor = 'green' } }").contains("leaves.backColor must be"),
            "{}",
            error("{ leaves = { backColor = 'green' } }")
        );
        let o = parse("{ mesh = { bark = 'smooth', flare = true } }").expect("ok");
        assert_eq!(o.mesh.bark, BarkStyle::Smooth);
        assert_eq!(o.mesh.flare, Some(Flare::default()));
        assert!(
            error("{ mesh = { light = {0, 0, 0} } }")
                .contains("mesh.light must be a non-zero direction")
        );
    }

    #[test]
    fn twig_cards_and_cards_along_the_branches() {
        let o = parse("{ leaves = { perCard = 7, along = { orders = 3, spacing = 0.5 } } }")
            .expect("ok");
        let l = o.leaves.expect("leaves");
        assert_eq!(l.per_card, 7);
        assert_eq!(
            l.along,
            Some(Along {
                orders: 3,
                spacing: 0.5
            })
        );
        assert_eq!(l.source, "eval:1");
        let o = parse("{ leaves = { along = true } }").expect("ok");
        assert_eq!(o.leaves.expect("leaves").along, Some(Along::default()));
    }

    #[test]
    fn shorthand_forms() {
        let o = parse(
            "{ leaves = { perTip = 2, colors = '#ff0000' }, mesh = { mergeStraight = true } }",
        )
        .expect("ok");
        let l = o.leaves.expect("leaves");
        assert_eq!(l.per_tip, (2, 2));
        assert_eq!(l.colors[0], l.colors[1]);
        assert_eq!(o.mesh.merge_straight, Some(5.0));
        assert!(parse("{ leaves = true }").expect("ok").leaves.is_some());
        assert!(parse("{ leaves = false }").expect("ok").leaves.is_none());
    }

    /// Runs `source` with a global `opts(t)` that parses tree options and returns the leaf
    /// texture source as text.
    fn run(dir: &std::path::Path, source: &str) -> pge_engine::Result<()> {
        let script = dir.join("t.lua");
        std::fs::write(&script, source).expect("write");
        let session = session();
        let f = session
            .lua()
            .create_function(|lua, t: Table| {
                tree_options(&Options::from_table(lua, t, "tree"))
                    .map(|o| format!("{:?}", o.leaves.map(|l| l.texture)))
            })
            .expect("function");
        session.lua().globals().set("opts", f).expect("global");
        session.run_script(&script).map(|_| ())
    }

    #[test]
    fn textures_load_next_to_the_script_and_errors_are_located() {
        let dir = tempfile::tempdir().expect("tempdir");
        let png =
            pge_engine::geometry::Texture::from_rgba("x", 1, 1, &[1, 2, 3, 255]).expect("png");
        std::fs::write(dir.path().join("leaf.png"), &png.encoded).expect("write png");
        run(
            dir.path(),
            "local s = opts{ leaves = { texture = 'leaf.png' } }\nassert(s:find('Image'), s)",
        )
        .expect("loads");
        let e = run(
            dir.path(),
            "\nlocal s = opts{ leaves = { texture = 'none.png' } }",
        )
        .expect_err("missing");
        let e = e.to_string();
        assert!(e.contains("t.lua:2: tree: leaves.texture: "), "{e}");
        assert!(e.contains("none.png"), "{e}");
        let e = run(dir.path(), "local s = opts{ mesh = { sides = 100 } }")
            .expect_err("range")
            .to_string();
        assert!(
            e.contains("t.lua:1: tree: mesh.sides must be an integer between 3 and 64, got 100"),
            "{e}"
        );
    }
}
