//! Lines and images, the thesis' behaviour modellers (§3.5): [`Lines`] draws coloured 3D
//! segments (fireworks, explorers' trails) exported as glTF lines; [`Image`] is a picture
//! scripts create or load, read and write pixel by pixel, save as PNG and use as a texture
//! (the explorers' map). [`CanvasPlugin`] adds them to scripts:
//!
//! ```lua
//! local lines = pge.Lines{ color = "#ffffff" }
//! lines:add({0, 0, 0}, {0, 1, 0}, "#ff4000")       -- a, b [, colour]
//! local map = pge.Image.load("map.png")            -- or pge.Image.new(w, h [, fill])
//! if map:getHex(3, 4) == "#00ff00" then map:set(3, 4, "#ffffff") end
//! map:save("out/map.png")                          -- beside the output (or the script)
//! local m = pge.model()
//! m:add(lines) m:add(map)                          -- the image as a textured plane
//! m:add(map:applyTo(pge.Extruder()))               -- or as the texture of any model
//! return m
//! ```

mod image;
mod lines;
#[cfg(feature = "lua")]
mod lua;

pub use crate::image::{Image, ImageError, MAX_PIXELS};
pub use lines::{Lines, LinesError, MAX_SEGMENTS};
#[cfg(feature = "lua")]
pub use lua::{LuaImage, LuaLines, LuaTexture};

#[cfg(feature = "lua")]
/// Registers `pge.Lines` and `pge.Image`.
#[derive(Clone, Copy, Debug, Default)]
pub struct CanvasPlugin;

#[cfg(feature = "lua")]
impl pge_engine::Plugin for CanvasPlugin {
    fn name(&self) -> &str {
        "canvas"
    }

    fn lazy_names(&self) -> &'static [&'static str] {
        &["Lines", "Image"]
    }

    fn register(&self, lua: &mlua::Lua, pge: &mlua::Table) -> mlua::Result<()> {
        lua::register(lua, pge)
    }
}
