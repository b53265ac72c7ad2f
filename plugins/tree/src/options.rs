//! Options of tree meshing and leaves, and their parsing from a Lua options table.
//!
//! The same options serve every tree generator (space colonization, the turtle, growth), so
//! a species reads the same whatever grew its skeleton. In Lua (API.md §5):
//!
//! ```lua
//! {
//!   radius = { tip = 0.02, exponent = 2.3 },   -- shorthand for mesh.tipRadius / mesh.exponent
//!   smoothing = 0.5,                           -- shorthand for mesh.smoothing
//!   sides = 8,                                 -- shorthand for mesh.sides
//!   mesh = { sides = 8, caps = true, exponent = 2.3, tipRadius = 0.02, mergeStraight = 5,
//!            smoothing = 0, radii = "pipe", color = "#6b5444", texture = "bark.png" },
//!   leaves = { perTip = {3, 6}, size = 0.25, width = 1, colors = {"#2f6b1f", "#7da83a"}, maxDepth = 2,
//!              texture = "leaf.png" },
//! }
//! ```
//! Keys inside `mesh` take precedence over the shorthands. Unknown keys inside `mesh` and
//! `leaves` are errors; other top-level keys belong to the generator and are ignored here.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

use mlua::{Table, Value};
use pge_engine::geometry::{Material, Texture};

/// A bad option: which one (`mesh.sides`, `leaves.perTip`) and what it needs.
///
/// Prints as `mesh.sides must be an integer between 3 and 64, got 2`; a Lua adapter turns it
/// into a `FILE:LINE:` error with `pge_engine::lua::script_error`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{option} {message}")]
pub struct OptionError {
    /// The option's path as the script spells it, e.g. `leaves.maxDepth`.
    pub option: String,
    /// What was wrong, starting with a verb: `must be ...`, `is unknown ...`.
    pub message: String,
}

impl OptionError {
    /// An error about `option`.
    #[must_use]
    pub fn new(option: impl Into<String>, message: impl Into<String>) -> OptionError {
        OptionError {
            option: option.into(),
            message: message.into(),
        }
    }
}

/// How branch radii are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RadiiMode {
    /// The pipe model from the tip radius: `r^n = r1^n + r2^n` at every fork (Lua `"pipe"`).
    #[default]
    Pipe,
    /// The radii already in the skeleton are kept (a turtle's widths; Lua `"keep"`).
    Keep,
}

/// Where a texture comes from.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum TextureSource {
    /// Generated procedurally (bark noise, leaf silhouette), no files needed.
    #[default]
    Procedural,
    /// A PNG file, read when the tree is built. A Lua adapter resolves the script's relative
    /// path (with `pge_engine::lua::resolve_path`) or loads the image itself.
    File(PathBuf),
    /// An image already loaded.
    Image(Arc<Texture>),
}

/// How the skeleton becomes the bark mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Points per ring (3..=64, default 8); each ring has one more vertex for the UV seam.
    pub sides: u32,
    /// Close branch tips (and the base of each root) with a flat cap (default true).
    pub caps: bool,
    /// Pipe-model exponent `n` in `r^n = r1^n + r2^n` (1..=4, default 2.3).
    pub exponent: f32,
    /// Radius at branch tips for the pipe model (> 0, default 0.02).
    pub tip_radius: f32,
    /// Merge non-branching nodes whose chain turns less than this many degrees (0..=45);
    /// `None` (default) keeps every node.
    pub merge_straight: Option<f32>,
    /// Move each node this fraction of the way toward its parent (0..=1, default 0; seed 000
    /// uses 0.5), which lowers branching angles.
    pub smoothing: f32,
    /// Pipe model or keep the skeleton's radii.
    pub radii: RadiiMode,
    /// Bark colour (sRGB `#rrggbb`, stored linear) used by the procedural bark texture.
    pub color: [f32; 4],
    /// The bark texture.
    pub texture: TextureSource,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            sides: 8,
            caps: true,
            exponent: 2.3,
            tip_radius: 0.02,
            merge_straight: None,
            smoothing: 0.0,
            radii: RadiiMode::Pipe,
            color: hex(DEFAULT_BARK),
            texture: TextureSource::Procedural,
        }
    }
}

/// Leaves hung at branch tips.
#[derive(Clone, Debug, PartialEq)]
pub struct LeafOptions {
    /// Leaves per tip, drawn uniformly in `min..=max` (default 3..=6; max 1000).
    pub per_tip: (u32, u32),
    /// Leaf length (> 0, default 0.25).
    pub size: f32,
    /// Leaf width as a fraction of its length (> 0 and at most 4, default 1: square quads;
    /// 0.2 gives needles).
    pub width: f32,
    /// Each leaf's colour is drawn between these two (linear RGBA).
    pub colors: [[f32; 4]; 2],
    /// A tip's leaves hang on its last `max_depth + 1` segments: 0 puts them on the tip
    /// segment only (0..=1000, default 2).
    pub max_depth: u32,
    /// The leaf texture (alpha-masked silhouette).
    pub texture: TextureSource,
}

impl Default for LeafOptions {
    fn default() -> Self {
        LeafOptions {
            per_tip: (3, 6),
            size: 0.25,
            width: 1.0,
            colors: [hex(DEFAULT_LEAF_COLORS[0]), hex(DEFAULT_LEAF_COLORS[1])],
            max_depth: 2,
            texture: TextureSource::Procedural,
        }
    }
}

/// Everything [`build_tree`](crate::build_tree) needs besides the skeleton.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TreeOptions {
    /// Bark meshing and radii.
    pub mesh: MeshOptions,
    /// Tip leaves; `None` for none. Leaf points already in the skeleton (a turtle's `~`) are
    /// meshed either way, styled by these options or their defaults.
    pub leaves: Option<LeafOptions>,
    /// Foliage levels of detail (API.md §6-7): the leaf mesh is simplified and written in
    /// the order of the vector V with its LOD table in the extras; `None` for none.
    pub lod: Option<pge_lod::LodOptions>,
}

const DEFAULT_BARK: &str = "#6b5444";
const DEFAULT_LEAF_COLORS: [&str; 2] = ["#2f6b1f", "#7da83a"];

const MESH_KEYS: &[&str] = &[
    "sides",
    "caps",
    "exponent",
    "tipRadius",
    "mergeStraight",
    "smoothing",
    "radii",
    "color",
    "texture",
];
const LEAF_KEYS: &[&str] = &["perTip", "size", "width", "colors", "maxDepth", "texture"];
const RADIUS_KEYS: &[&str] = &["tip", "exponent"];

fn hex(s: &str) -> [f32; 4] {
    Material::from_hex("", s)
        .map(|m| m.base_color)
        .unwrap_or([1.0; 4])
}

impl TreeOptions {
    /// Reads the tree options from a generator's Lua options table (see the module docs):
    /// `mesh`, `leaves`, and the shorthands `radius = {tip, exponent}`, `smoothing`, `sides`.
    /// Other keys are ignored (they belong to the generator).
    pub fn from_lua(table: &Table) -> Result<TreeOptions, OptionError> {
        let mut mesh = MeshOptions::default();
        match get(table, "radius", "radius")? {
            Value::Nil => {}
            Value::Table(t) => {
                check_keys(&t, "radius", RADIUS_KEYS)?;
                if let Some(v) = number_in(&t, "tip", "radius.tip", 0.0, f32::MAX, false)? {
                    mesh.tip_radius = v;
                }
                if let Some(v) = number_in(&t, "exponent", "radius.exponent", 1.0, 4.0, true)? {
                    mesh.exponent = v;
                }
            }
            Value::Integer(_) | Value::Number(_) => {
                if let Some(v) = number_in(table, "radius", "radius", 0.0, f32::MAX, false)? {
                    mesh.tip_radius = v;
                }
            }
            other => {
                return Err(OptionError::new(
                    "radius",
                    format!(
                        "must be a table {{tip = r, exponent = n}}, got {}",
                        other.type_name()
                    ),
                ));
            }
        }
        if let Some(v) = number_in(table, "smoothing", "smoothing", 0.0, 1.0, true)? {
            mesh.smoothing = v;
        }
        if let Some(v) = integer_in(table, "sides", "sides", 3, 64)? {
            mesh.sides = v;
        }
        match get(table, "mesh", "mesh")? {
            Value::Nil => {}
            Value::Table(t) => mesh.read_lua(&t, "mesh")?,
            other => {
                return Err(OptionError::new(
                    "mesh",
                    format!("must be a table of mesh options, got {}", other.type_name()),
                ));
            }
        }
        let leaves = match get(table, "leaves", "leaves")? {
            Value::Nil | Value::Boolean(false) => None,
            Value::Boolean(true) => Some(LeafOptions::default()),
            Value::Table(t) => Some(LeafOptions::from_lua_at(&t, "leaves")?),
            other => {
                return Err(OptionError::new(
                    "leaves",
                    format!(
                        "must be a table of leaf options or false, got {}",
                        other.type_name()
                    ),
                ));
            }
        };
        Ok(TreeOptions {
            mesh,
            leaves,
            lod: None,
        })
    }
}

impl MeshOptions {
    /// Reads a `mesh = {...}` table: `sides`, `caps`, `exponent`, `tipRadius`,
    /// `mergeStraight` (degrees, or a boolean: true is 5 degrees), `smoothing`, `radii`
    /// (`"pipe"` or `"keep"`), `color`, `texture` (a PNG path). Absent keys keep defaults.
    pub fn from_lua(table: &Table) -> Result<MeshOptions, OptionError> {
        let mut options = MeshOptions::default();
        options.read_lua(table, "mesh")?;
        Ok(options)
    }

    fn read_lua(&mut self, t: &Table, at: &str) -> Result<(), OptionError> {
        check_keys(t, at, MESH_KEYS)?;
        let path = |k: &str| format!("{at}.{k}");
        if let Some(v) = integer_in(t, "sides", &path("sides"), 3, 64)? {
            self.sides = v;
        }
        if let Some(v) = boolean(t, "caps", &path("caps"))? {
            self.caps = v;
        }
        if let Some(v) = number_in(t, "exponent", &path("exponent"), 1.0, 4.0, true)? {
            self.exponent = v;
        }
        if let Some(v) = number_in(t, "tipRadius", &path("tipRadius"), 0.0, f32::MAX, false)? {
            self.tip_radius = v;
        }
        match get(t, "mergeStraight", &path("mergeStraight"))? {
            Value::Nil => {}
            Value::Boolean(b) => self.merge_straight = b.then_some(5.0),
            _ => {
                self.merge_straight =
                    number_in(t, "mergeStraight", &path("mergeStraight"), 0.0, 45.0, true)?;
            }
        }
        if let Some(v) = number_in(t, "smoothing", &path("smoothing"), 0.0, 1.0, true)? {
            self.smoothing = v;
        }
        if let Some(s) = string(t, "radii", &path("radii"))? {
            self.radii = match s.as_str() {
                "pipe" => RadiiMode::Pipe,
                "keep" => RadiiMode::Keep,
                _ => {
                    return Err(OptionError::new(
                        path("radii"),
                        format!("must be \"pipe\" or \"keep\", got \"{s}\""),
                    ));
                }
            };
        }
        if let Some(s) = string(t, "color", &path("color"))? {
            self.color = color(&s, &path("color"))?;
        }
        if let Some(s) = string(t, "texture", &path("texture"))? {
            self.texture = TextureSource::File(PathBuf::from(s));
        }
        Ok(())
    }
}

impl LeafOptions {
    /// Reads a `leaves = {...}` table: `perTip = {min, max}` (or one number), `size`, `width`,
    /// `colors = {"#rrggbb", "#rrggbb"}` (or one colour), `maxDepth`, `texture` (a PNG path).
    pub fn from_lua(table: &Table) -> Result<LeafOptions, OptionError> {
        LeafOptions::from_lua_at(table, "leaves")
    }

    fn from_lua_at(t: &Table, at: &str) -> Result<LeafOptions, OptionError> {
        check_keys(t, at, LEAF_KEYS)?;
        let path = |k: &str| format!("{at}.{k}");
        let mut o = LeafOptions::default();
        match get(t, "perTip", &path("perTip"))? {
            Value::Nil => {}
            Value::Table(range) => {
                let p = path("perTip");
                let min = integer_in(&range, 1, &format!("{p}[1]"), 0, 1000)?;
                let max = integer_in(&range, 2, &format!("{p}[2]"), 0, 1000)?;
                let (Some(min), Some(max)) = (min, max) else {
                    return Err(OptionError::new(
                        p,
                        "must be {min, max} with 0 <= min <= max <= 1000",
                    ));
                };
                if min > max {
                    return Err(OptionError::new(
                        p,
                        format!("must have min <= max, got {{{min}, {max}}}"),
                    ));
                }
                o.per_tip = (min, max);
            }
            _ => {
                if let Some(n) = integer_in(t, "perTip", &path("perTip"), 0, 1000)? {
                    o.per_tip = (n, n);
                }
            }
        }
        if let Some(v) = number_in(t, "size", &path("size"), 0.0, f32::MAX, false)? {
            o.size = v;
        }
        if let Some(v) = number_in(t, "width", &path("width"), 0.0, 4.0, false)? {
            o.width = v;
        }
        match get(t, "colors", &path("colors"))? {
            Value::Nil => {}
            Value::String(s) => {
                let c = color(&s.to_string_lossy(), &path("colors"))?;
                o.colors = [c, c];
            }
            Value::Table(list) => {
                let p = path("colors");
                let a = string(&list, 1, &format!("{p}[1]"))?;
                let b = string(&list, 2, &format!("{p}[2]"))?;
                match (a, b) {
                    (Some(a), Some(b)) => {
                        o.colors = [
                            color(&a, &format!("{p}[1]"))?,
                            color(&b, &format!("{p}[2]"))?,
                        ];
                    }
                    (Some(a), None) => {
                        let c = color(&a, &format!("{p}[1]"))?;
                        o.colors = [c, c];
                    }
                    _ => {
                        return Err(OptionError::new(p, "must be {\"#rrggbb\", \"#rrggbb\"}"));
                    }
                }
            }
            other => {
                return Err(OptionError::new(
                    path("colors"),
                    format!(
                        "must be {{\"#rrggbb\", \"#rrggbb\"}}, got {}",
                        other.type_name()
                    ),
                ));
            }
        }
        if let Some(v) = integer_in(t, "maxDepth", &path("maxDepth"), 0, 1000)? {
            o.max_depth = v;
        }
        if let Some(s) = string(t, "texture", &path("texture"))? {
            o.texture = TextureSource::File(PathBuf::from(s));
        }
        Ok(o)
    }
}

/// Checks that every string key of `t` is one of `known`.
fn check_keys(t: &Table, at: &str, known: &[&str]) -> Result<(), OptionError> {
    for pair in t.pairs::<Value, Value>() {
        let (k, _) = pair.map_err(|e| OptionError::new(at, format!("could not be read: {e}")))?;
        if let Value::String(s) = &k {
            let name = s.to_string_lossy();
            if !known.contains(&name.as_str()) {
                return Err(OptionError::new(
                    format!("{at}.{name}"),
                    format!("is not an option (known: {})", known.join(", ")),
                ));
            }
        }
    }
    Ok(())
}

fn get(t: &Table, key: impl mlua::IntoLua, path: &str) -> Result<Value, OptionError> {
    t.get::<Value>(key)
        .map_err(|e| OptionError::new(path, format!("could not be read: {e}")))
}

/// A finite number in `[lo, hi]` (`(lo, hi]` when `!closed_lo`), or `None` when absent.
fn number_in(
    t: &Table,
    key: impl mlua::IntoLua,
    path: &str,
    lo: f32,
    hi: f32,
    closed_lo: bool,
) -> Result<Option<f32>, OptionError> {
    let range = || {
        let low = if closed_lo {
            format!("between {lo} and")
        } else {
            format!("greater than {lo} and at most")
        };
        if hi == f32::MAX {
            if closed_lo {
                format!("a number >= {lo}")
            } else {
                format!("a number > {lo}")
            }
        } else {
            format!("a number {low} {hi}")
        }
    };
    let v = match get(t, key, path)? {
        Value::Nil => return Ok(None),
        Value::Integer(i) => i as f64,
        Value::Number(n) => n,
        other => {
            return Err(OptionError::new(
                path,
                format!("must be {}, got {}", range(), other.type_name()),
            ));
        }
    };
    let ok = v.is_finite()
        && (if closed_lo {
            v >= lo as f64
        } else {
            v > lo as f64
        })
        && v <= hi as f64;
    if !ok {
        return Err(OptionError::new(
            path,
            format!("must be {}, got {v}", range()),
        ));
    }
    Ok(Some(v as f32))
}

/// An integer in `lo..=hi`, or `None` when absent.
fn integer_in(
    t: &Table,
    key: impl mlua::IntoLua,
    path: &str,
    lo: u32,
    hi: u32,
) -> Result<Option<u32>, OptionError> {
    let bad = |got: String| {
        OptionError::new(
            path,
            format!("must be an integer between {lo} and {hi}, got {got}"),
        )
    };
    let v = match get(t, key, path)? {
        Value::Nil => return Ok(None),
        Value::Integer(i) => i,
        Value::Number(n) if n.fract() == 0.0 && n.abs() < 1e15 => n as i64,
        Value::Number(n) => return Err(bad(n.to_string())),
        other => return Err(bad(other.type_name().to_string())),
    };
    if v < lo as i64 || v > hi as i64 {
        return Err(bad(v.to_string()));
    }
    Ok(Some(v as u32))
}

fn boolean(t: &Table, key: &str, path: &str) -> Result<Option<bool>, OptionError> {
    match get(t, key, path)? {
        Value::Nil => Ok(None),
        Value::Boolean(b) => Ok(Some(b)),
        other => Err(OptionError::new(
            path,
            format!("must be true or false, got {}", other.type_name()),
        )),
    }
}

fn string(t: &Table, key: impl mlua::IntoLua, path: &str) -> Result<Option<String>, OptionError> {
    match get(t, key, path)? {
        Value::Nil => Ok(None),
        Value::String(s) => Ok(Some(s.to_string_lossy())),
        other => Err(OptionError::new(
            path,
            format!("must be a string, got {}", other.type_name()),
        )),
    }
}

fn color(s: &str, path: &str) -> Result<[f32; 4], OptionError> {
    Material::from_hex("", s)
        .map(|m| m.base_color)
        .map_err(|_| OptionError::new(path, format!("must be a colour \"#rrggbb\", got \"{s}\"")))
}

impl fmt::Display for RadiiMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RadiiMode::Pipe => "pipe",
            RadiiMode::Keep => "keep",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mlua::Lua;

    fn parse(src: &str) -> Result<TreeOptions, OptionError> {
        let lua = Lua::new();
        let t: Table = lua.load(src).eval().expect("valid lua");
        TreeOptions::from_lua(&t)
    }

    #[test]
    fn defaults_when_empty() {
        let o = parse("return {}").expect("ok");
        assert_eq!(o, TreeOptions::default());
        assert_eq!(o.mesh.sides, 8);
        assert_eq!(o.mesh.exponent, 2.3);
        assert!(o.leaves.is_none());
    }

    #[test]
    fn reads_every_option_and_mesh_wins_over_shorthands() {
        let o = parse(
            r##"return { radius = {tip = 0.05, exponent = 2.5}, smoothing = 0.5, sides = 6,
                mesh = { sides = 12, caps = false, mergeStraight = 3, radii = "keep",
                         color = "#ffffff", texture = "bark.png" },
                leaves = { perTip = {1, 4}, size = 0.3, width = 0.25, colors = {"#000000", "#ffffff"},
                           maxDepth = 3, texture = "leaf.png" }, other = 1 }"##,
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
        assert_eq!(o.mesh.texture, TextureSource::File("bark.png".into()));
        let l = o.leaves.expect("leaves");
        assert_eq!(l.per_tip, (1, 4));
        assert_eq!(l.size, 0.3);
        assert_eq!(l.width, 0.25);
        assert_eq!(l.colors, [[0.0, 0.0, 0.0, 1.0], [1.0; 4]]);
        assert_eq!(l.max_depth, 3);
        assert_eq!(l.texture, TextureSource::File("leaf.png".into()));
    }

    #[test]
    fn errors_name_the_option_and_its_range() {
        let cases = [
            (
                "return { mesh = { sides = 2 } }",
                "mesh.sides must be an integer between 3 and 64, got 2",
            ),
            (
                "return { sides = 2.5 }",
                "sides must be an integer between 3 and 64, got 2.5",
            ),
            (
                "return { radius = { tip = -1 } }",
                "radius.tip must be a number > 0, got -1",
            ),
            (
                "return { radius = { tip = 0/0 } }",
                "radius.tip must be a number > 0, got NaN",
            ),
            (
                "return { mesh = { exponent = 9 } }",
                "mesh.exponent must be a number between 1 and 4, got 9",
            ),
            (
                "return { smoothing = 'x' }",
                "smoothing must be a number between 0 and 1, got string",
            ),
            (
                "return { mesh = { radii = 'x' } }",
                "mesh.radii must be \"pipe\" or \"keep\", got \"x\"",
            ),
            (
                "return { leaves = { perTip = {5, 2} } }",
                "leaves.perTip must have min <= max, got {5, 2}",
            ),
            (
                "return { leaves = { colors = {'red'} } }",
                "leaves.colors[1] must be a colour \"#rrggbb\", got \"red\"",
            ),
            (
                "return { leaves = { maxDepth = -1 } }",
                "leaves.maxDepth must be an integer between 0 and 1000, got -1",
            ),
            (
                "return { leaves = 3 }",
                "leaves must be a table of leaf options or false, got integer",
            ),
        ];
        for (src, want) in cases {
            assert_eq!(parse(src).expect_err(src).to_string(), want, "{src}");
        }
        let e = parse("return { mesh = { side = 3 } }").expect_err("unknown");
        assert_eq!(e.option, "mesh.side");
        assert!(e.message.contains("known: sides, caps"), "{}", e.message);
    }

    #[test]
    fn shorthand_forms() {
        let o = parse("return { leaves = { perTip = 2, colors = '#ff0000' }, mesh = { mergeStraight = true } }")
            .expect("ok");
        let l = o.leaves.expect("leaves");
        assert_eq!(l.per_tip, (2, 2));
        assert_eq!(l.colors[0], l.colors[1]);
        assert_eq!(o.mesh.merge_straight, Some(5.0));
        assert!(
            parse("return { leaves = true }")
                .expect("ok")
                .leaves
                .is_some()
        );
        assert!(
            parse("return { leaves = false }")
                .expect("ok")
                .leaves
                .is_none()
        );
    }
}
