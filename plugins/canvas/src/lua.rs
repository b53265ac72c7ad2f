//! The Lua side: `pge.Lines{...}` and `pge.Image.new` / `pge.Image.load`.

use pge_engine::math;
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use glam::Vec4;
use mlua::{Lua, MultiValue, Table, UserData, UserDataMethods, Value};
use pge_engine::geometry::{Model, Texture};
use pge_engine::lua::{
    Bounds, LuaMesh, LuaModel, Options, caller_location, finite_number, memory_budget, read_file,
    resolve_path, run_context, script_error, to_model, vec3_arg, write_inside,
};

use crate::{Image, Lines};

/// An sRGB colour as bytes: `"#rrggbb"`, `"#rrggbbaa"`, or `{r, g, b [, a]}` in [0, 1].
fn rgba_bytes(lua: &Lua, v: &Value, what: &str) -> mlua::Result<[u8; 4]> {
    let bad = |msg: String| script_error(lua, format!("{what}: {msg}"));
    match v {
        Value::String(s) => {
            let s = s.to_str()?;
            let digits = s.strip_prefix('#').unwrap_or(&s);
            let byte = |i: usize| u8::from_str_radix(digits.get(i..i + 2).unwrap_or("x"), 16);
            let parsed = match digits.len() {
                6 => (byte(0), byte(2), byte(4), Ok(255)),
                8 => (byte(0), byte(2), byte(4), byte(6)),
                _ => {
                    return Err(bad(format!(
                        "'{}' is not a colour: expected \"#rrggbb\" or \"#rrggbbaa\"",
                        &*s
                    )));
                }
            };
            match parsed {
                (Ok(r), Ok(g), Ok(b), Ok(a)) => Ok([r, g, b, a]),
                _ => Err(bad(format!(
                    "'{}' is not a colour: expected \"#rrggbb\" or \"#rrggbbaa\"",
                    &*s
                ))),
            }
        }
        Value::Table(t) => {
            let n = t.raw_len();
            if !(3..=4).contains(&n) {
                return Err(bad(format!(
                    "a colour table needs 3 or 4 numbers in [0, 1], got {n}"
                )));
            }
            let mut out = [255u8; 4];
            for (i, slot) in out.iter_mut().enumerate().take(n) {
                let x = finite_number(lua, &t.raw_get::<Value>(i + 1)?, what)?;
                if !(0.0..=1.0).contains(&x) {
                    return Err(bad(format!("colour component {x} is outside [0, 1]")));
                }
                *slot = (x * 255.0).round() as u8;
            }
            Ok(out)
        }
        other => Err(bad(format!(
            "expected a colour \"#rrggbb\" or {{r, g, b}}, got {}",
            other.type_name()
        ))),
    }
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        math::powf((c + 0.055) / 1.055, 2.4)
    }
}

/// A colour for a vertex: the sRGB input made linear.
fn linear(lua: &Lua, v: &Value, what: &str) -> mlua::Result<Vec4> {
    let [r, g, b, a] = rgba_bytes(lua, v, what)?.map(|c| c as f32 / 255.0);
    Ok(Vec4::new(
        srgb_to_linear(r),
        srgb_to_linear(g),
        srgb_to_linear(b),
        a,
    ))
}

/// `pge.Lines{ color = "#ffffff" }`: coloured segments.
#[derive(Clone)]
pub struct LuaLines(pub Rc<RefCell<Lines>>);

impl UserData for LuaLines {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "line set");
        m.add_method("add", |lua, me, (a, b, c): (Value, Value, Value)| {
            pge_engine::lua::check_mutable(lua, "lines:add")?;
            let a = vec3_arg(lua, a, "add(a, b [, colour])")?;
            let b = vec3_arg(lua, b, "add(a, b [, colour])")?;
            let c = match c {
                Value::Nil => None,
                c => Some(linear(lua, &c, "add: colour")?),
            };
            me.0.borrow_mut()
                .add(a, b, c)
                .map_err(|e| script_error(lua, format!("add: {e}")))
        });
        m.add_method("count", |_, me, ()| Ok(me.0.borrow().len()));
        m.add_method("clear", |lua, me, ()| {
            pge_engine::lua::check_mutable(lua, "lines:clear")?;
            me.0.borrow_mut().clear();
            Ok(())
        });
        m.add_method("mesh", |_, me, ()| {
            Ok(LuaMesh(Arc::new(me.0.borrow().mesh())))
        });
        m.add_method("model", |_, me, ()| {
            let lines = me.0.borrow();
            Ok(LuaModel(if lines.is_empty() {
                Model::new()
            } else {
                Model::from_mesh(lines.mesh())
            }))
        });
    }
}

/// `pge.Image.new(w, h)` / `pge.Image.load(path)`.
#[derive(Clone)]
pub struct LuaImage(pub Rc<RefCell<Image>>);

/// What `image:texture()` returns: a snapshot of the image as a PNG texture, for a
/// material's `texture`.
#[derive(Clone, Debug)]
pub struct LuaTexture(pub Arc<Texture>);

impl UserData for LuaTexture {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        m.add_method("width", |_, me, ()| Ok(me.0.width));
        m.add_method("height", |_, me, ()| Ok(me.0.height));
        m.add_method("pngBytes", |lua, me, ()| lua.create_string(&me.0.encoded));
    }
}

/// `img` as a script value, its pixels charged to the run's memory budget for as long as the
/// script keeps it (`what` names it in the error when the budget is short).
fn image_value(lua: &Lua, img: Image, what: &str) -> mlua::Result<mlua::AnyUserData> {
    let bytes = img.width() as usize * img.height() as usize * 4;
    let value = lua.create_userdata(LuaImage(Rc::new(RefCell::new(img))))?;
    pge_engine::lua::charge(lua, &value, bytes, what)?;
    Ok(value)
}

/// A pixel coordinate: a whole number (range is checked by the image).
fn coord(lua: &Lua, v: &Value, what: &str) -> mlua::Result<i64> {
    let x = finite_number(lua, v, what)?;
    if x.fract() != 0.0 {
        return Err(script_error(
            lua,
            format!("{what}: pixel coordinate {x} is not a whole number"),
        ));
    }
    Ok(x as i64)
}

impl UserData for LuaImage {
    fn add_methods<M: UserDataMethods<Self>>(m: &mut M) {
        pge_engine::lua::no_new_fields(m, "image");
        m.add_method("width", |_, me, ()| Ok(me.0.borrow().width()));
        m.add_method("height", |_, me, ()| Ok(me.0.borrow().height()));
        m.add_method("inside", |lua, me, (x, y): (Value, Value)| {
            let (x, y) = (
                finite_number(lua, &x, "inside(x, y)")?,
                finite_number(lua, &y, "inside(x, y)")?,
            );
            Ok(x.fract() == 0.0 && y.fract() == 0.0 && me.0.borrow().contains(x as i64, y as i64))
        });
        m.add_method("get", |lua, me, (x, y): (Value, Value)| {
            let (x, y) = (coord(lua, &x, "get(x, y)")?, coord(lua, &y, "get(x, y)")?);
            let px =
                me.0.borrow()
                    .get(x, y)
                    .map_err(|e| script_error(lua, format!("get: {e}")))?;
            let [r, g, b, a] = px.map(|c| f64::from(c) / 255.0);
            Ok((r, g, b, a))
        });
        m.add_method("getHex", |lua, me, (x, y): (Value, Value)| {
            let (x, y) = (
                coord(lua, &x, "getHex(x, y)")?,
                coord(lua, &y, "getHex(x, y)")?,
            );
            let [r, g, b, a] =
                me.0.borrow()
                    .get(x, y)
                    .map_err(|e| script_error(lua, format!("getHex: {e}")))?;
            Ok(if a == 255 {
                format!("#{r:02x}{g:02x}{b:02x}")
            } else {
                format!("#{r:02x}{g:02x}{b:02x}{a:02x}")
            })
        });
        m.add_method("set", |lua, me, args: MultiValue| {
            pge_engine::lua::check_mutable(lua, "image:set")?;
            let args: Vec<Value> = args.into_iter().collect();
            if args.len() < 3 {
                return Err(script_error(
                    lua,
                    "set(x, y, colour): expected x, y and a colour",
                ));
            }
            let (x, y) = (
                coord(lua, &args[0], "set(x, y, colour)")?,
                coord(lua, &args[1], "set(x, y, colour)")?,
            );
            let px = if args.len() >= 5 {
                // set(x, y, r, g, b [, a])
                let t = lua.create_sequence_from(args[2..].iter().take(4).cloned())?;
                rgba_bytes(lua, &Value::Table(t), "set: colour")?
            } else {
                rgba_bytes(lua, &args[2], "set: colour")?
            };
            me.0.borrow_mut()
                .set(x, y, px)
                .map_err(|e| script_error(lua, format!("set: {e}")))
        });
        m.add_method("fill", |lua, me, c: Value| {
            pge_engine::lua::check_mutable(lua, "image:fill")?;
            let px = rgba_bytes(lua, &c, "fill(colour)")?;
            me.0.borrow_mut().fill(px);
            Ok(())
        });
        m.add_method("save", |lua, me, path: Value| {
            let Value::String(p) = path else {
                return Err(script_error(lua, "save(path): expected a file name"));
            };
            let p = p.to_str()?.to_string();
            let is_png = std::path::Path::new(&p)
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png"));
            if !is_png {
                return Err(script_error(
                    lua,
                    format!("save('{p}'): the file name must end in .png"),
                ));
            }
            let png =
                me.0.borrow()
                    .png()
                    .map_err(|e| script_error(lua, format!("save: {e}")))?;
            write_inside(lua, &p, &png)?;
            Ok(())
        });
        m.add_method("clone", |lua, me, ()| {
            let copy = me.0.borrow().clone();
            image_value(lua, copy, "image:clone()")
        });
        m.add_method("texture", |lua, me, ()| {
            let t =
                me.0.borrow()
                    .texture("image")
                    .map_err(|e| script_error(lua, format!("texture: {e}")))?;
            // Held by the script: its bytes are charged to the run's budget while it lives.
            let t = Arc::new(t);
            pge_engine::lua::charge_texture(lua, &t)?;
            Ok(LuaTexture(t))
        });
        m.add_method("pngBytes", |lua, me, ()| {
            let png =
                me.0.borrow()
                    .png()
                    .map_err(|e| script_error(lua, format!("pngBytes: {e}")))?;
            lua.create_string(&png)
        });
        m.add_method("applyTo", |lua, me, thing: Value| {
            let mut model = to_model(&thing).map_err(|e| match e {
                mlua::Error::RuntimeError(_) => e,
                other => script_error(lua, format!("applyTo: {other}")),
            })?;
            let texture = Arc::new(
                me.0.borrow()
                    .texture("image")
                    .map_err(|e| script_error(lua, format!("applyTo: {e}")))?,
            );
            model.meshes = model
                .meshes
                .iter()
                .map(|mesh| {
                    let mut mesh = (**mesh).clone();
                    let mut material = (*mesh.material).clone();
                    material.texture = Some(texture.clone());
                    mesh.material = Arc::new(material);
                    Arc::new(mesh)
                })
                .collect();
            Ok(LuaModel(model))
        });
        m.add_method("model", |lua, me, ()| {
            let mesh =
                me.0.borrow()
                    .plane_mesh()
                    .map_err(|e| script_error(lua, format!("model: {e}")))?;
            Ok(LuaModel(Model::from_mesh(mesh)))
        });
    }
}

fn size(lua: &Lua, v: &Value, what: &str) -> mlua::Result<u32> {
    let x = finite_number(lua, v, what)?;
    if x.fract() != 0.0 || x < 1.0 || x > f64::from(u32::MAX) {
        return Err(script_error(
            lua,
            format!("{what}: the size must be a whole number of pixels, got {x}"),
        ));
    }
    Ok(x as u32)
}

/// An image (and its PNG when exported) must fit in what the run's memory budget has left:
/// else the typed memory limit at the calling line, naming the image.
fn check_image_budget(lua: &Lua, w: u64, h: u64, what: &str) -> mlua::Result<()> {
    let bytes = w.saturating_mul(h).saturating_mul(8);
    let budget = memory_budget(lua) as u64;
    if bytes > budget {
        let exceeded = run_context(lua).budget.exceeded(
            &caller_location(lua),
            Some(format!("{what}: a {w}x{h} image needs {} MiB", bytes >> 20)),
        );
        return Err(mlua::Error::external(exceeded));
    }
    Ok(())
}

/// Adds `pge.Lines` and `pge.Image`.
pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set(
        "Lines",
        lua.create_function(|lua, t: Value| {
            let o = Options::new(lua, t, "pge.Lines")?;
            let color = match o.value("color")? {
                Value::Nil => Vec4::ONE,
                c => linear(lua, &c, "pge.Lines: color")?,
            };
            let width = o.number_f32("width", Bounds::AtLeast(0.0))?.unwrap_or(0.0);
            o.finish()?;
            let per = if width > 0.0 {
                Lines::BYTES_PER_TUBE
            } else {
                Lines::BYTES_PER_SEGMENT
            };
            let max = memory_budget(lua) / per;
            Ok(LuaLines(Rc::new(RefCell::new(
                Lines::with_max_segments(color, max).with_width(width),
            ))))
        })?,
    )?;
    let image = lua.create_table()?;
    image.set(
        "new",
        lua.create_function(|lua, (w, h, fill): (Value, Value, Value)| {
            let (w, h) = (
                size(lua, &w, "pge.Image.new(w, h)")?,
                size(lua, &h, "pge.Image.new(w, h)")?,
            );
            let fill = match fill {
                Value::Nil => [0, 0, 0, 255],
                c => rgba_bytes(lua, &c, "pge.Image.new: fill colour")?,
            };
            check_image_budget(lua, u64::from(w), u64::from(h), "pge.Image.new")?;
            let img = Image::new(w, h, fill)
                .map_err(|e| script_error(lua, format!("pge.Image.new: {e}")))?;
            image_value(lua, img, "pge.Image.new")
        })?,
    )?;
    image.set(
        "load",
        lua.create_function(|lua, path: Value| {
            let Value::String(p) = path else {
                return Err(script_error(
                    lua,
                    "pge.Image.load(path): expected a file name",
                ));
            };
            let p = p.to_str()?.to_string();
            let file = resolve_path(lua, &p)?;
            let bytes = read_file(lua, &file)
                .map_err(|e| script_error(lua, format!("pge.Image.load '{p}': {e}")))?;
            let img = Image::decode(&bytes)
                .map_err(|e| script_error(lua, format!("pge.Image.load '{p}': {e}")))?;
            check_image_budget(
                lua,
                u64::from(img.width()),
                u64::from(img.height()),
                "pge.Image.load",
            )?;
            image_value(lua, img, "pge.Image.load")
        })?,
    )?;
    pge.set("Image", image)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use pge_engine::{Engine, Session};

    fn session() -> (Engine, Session) {
        let engine = Engine::builder()
            .plugin(crate::CanvasPlugin)
            .build()
            .expect("engine");
        let session = engine.session(Default::default()).expect("session");
        (engine, session)
    }

    #[test]
    fn lines_and_images_from_lua() {
        let (_e, s) = session();
        let (segments, hex, r, a, w): (usize, String, f64, f64, u32) = s
            .eval(
                "local l = pge.Lines{ color = '#ffffff' }
                 l:add({0, 0, 0}, {0, 1, 0})
                 l:add(pge.vec3(0, 1, 0), {1, 1, 0}, '#ff0000')
                 local img = pge.Image.new(8, 4, '#000000')
                 img:set(7, 3, '#ff8000')
                 img:set(0, 0, 1, 0, 0, 0.5)
                 local r, g, b, a = img:get(0, 0)
                 assert(img:texture():width() == 8)
                 assert(img:model():triangleCount() == 2)
                 local quad = pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2},
                                        uvs = {0,0, 1,0, 0,1} }
                 assert(img:applyTo(quad):triangleCount() == 1)
                 return l:count(), img:getHex(7, 3), r, a, img:width()",
            )
            .expect("runs");
        assert_eq!(segments, 2);
        assert_eq!(hex, "#ff8000");
        assert_eq!(r, 1.0);
        assert!((a - 128.0 / 255.0).abs() < 1e-9);
        assert_eq!(w, 8);
    }

    #[test]
    fn images_and_lines_respect_the_memory_limit() {
        let engine = Engine::builder()
            .plugin(crate::CanvasPlugin)
            .memory_limit_mib(64)
            .build()
            .expect("engine");
        let s = engine.session(Default::default()).expect("session");
        let err = s
            .eval::<()>("local a = 1\nlocal img = pge.Image.new(4096, 4096)")
            .expect_err("too big");
        assert!(
            err.to_string()
                == "eval:2: pge.Image.new: a 4096x4096 image needs 128 MiB: memory limit of 64 \
                    MiB exceeded (see --memory-limit)",
            "{err}"
        );
        s.eval::<()>("local img = pge.Image.new(1024, 1024)")
            .expect("fits");
    }

    #[test]
    fn mistakes_are_located_errors() {
        let (_e, s) = session();
        let cases = [
            (
                "local img = pge.Image.new(4, 4)\nimg:get(4, 0)",
                "eval:2: get: pixel (4, 0) is outside the 4x4 image",
            ),
            (
                "local img = pge.Image.new(4, 4)\nimg:set(0, -1, '#ffffff')",
                "eval:2: set: pixel (0, -1) is outside",
            ),
            (
                "local img = pge.Image.new(4, 4)\nimg:set(0.5, 1, '#ffffff')",
                "eval:2: set(x, y, colour): pixel coordinate 0.5",
            ),
            (
                "local img = pge.Image.new(0, 4)",
                "eval:1: pge.Image.new(w, h): the size must be",
            ),
            (
                "local img = pge.Image.new(4, 4)\nimg:set(0, 0, 'red')",
                "eval:2: set: colour: 'red' is not a colour",
            ),
            (
                "local l = pge.Lines()\nl:add({0, 0}, {1, 1, 1})",
                "eval:2: add(a, b [, colour]): a vector table needs three numbers",
            ),
            (
                "local img = pge.Image.new(4, 4)\nimg:save('/tmp/x.png')",
                "eval:2: cannot write '/tmp/x.png'",
            ),
            (
                "local img = pge.Image.new(4, 4)\nimg:save('notes.txt')",
                "eval:2: save('notes.txt'): the file name must end in .png",
            ),
            (
                "local img = pge.Image.new(4, 4)\nimg:save('../x.png')",
                "eval:2: cannot write '../x.png'",
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
