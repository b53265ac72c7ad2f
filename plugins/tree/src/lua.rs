//! The Lua side of tree options, shared by every generator's constructor
//! (`pge.SpaceColonization{...}`, `pge.turtle{...}`, `pge.Growth{...}`).

use mlua::{Lua, Table};
use pge_engine::lua::{caller_location, resolve_path, script_error};

use crate::options::{TextureSource, TreeOptions};
use crate::textures::load_png;

/// Reads [`TreeOptions`] from a generator's options table (see [`TreeOptions::from_lua`]),
/// then resolves texture paths next to the calling script (recorded for live reload) and
/// loads them. Every problem is a `FILE:LINE: WHAT: option ...` error at the calling line,
/// where `what` names the constructor (e.g. `pge.SpaceColonization`).
pub fn options_from_lua(lua: &Lua, what: &str, table: &Table) -> mlua::Result<TreeOptions> {
    let mut options =
        TreeOptions::from_lua(table).map_err(|e| script_error(lua, format!("{what}: {e}")))?;
    load_texture(lua, what, "mesh.texture", "bark", &mut options.mesh.texture)?;
    if let Some(leaves) = &mut options.leaves {
        load_texture(lua, what, "leaves.texture", "leaf", &mut leaves.texture)?;
    }
    Ok(options)
}

/// Reads a texture given as a file path, relative to the calling script and inside the
/// folders scripts may read (recorded for live reload), and replaces the path by the image.
/// `what` and `key` name the option in errors; `name` names the texture in the glb.
pub fn load_texture(
    lua: &Lua,
    what: &str,
    key: &str,
    name: &str,
    source: &mut TextureSource,
) -> mlua::Result<()> {
    if let TextureSource::File(path) = source {
        let shown = path.to_string_lossy().into_owned();
        let file = resolve_path(lua, &shown)
            .map_err(|e| script_error(lua, format!("{what}: {key}: {}", unlocated(lua, &e))))?;
        let texture = load_png(&file, name)
            .map_err(|e| script_error(lua, format!("{what}: {key}: cannot read '{shown}': {e}")))?;
        *source = TextureSource::Image(texture);
    }
    Ok(())
}

/// The first line of an error's message without the `FILE:LINE: ` of the calling code that
/// the engine's helpers already put in front (the caller adds it again with its own prefix).
fn unlocated(lua: &Lua, e: &mlua::Error) -> String {
    let message = match e {
        mlua::Error::RuntimeError(m) => m.clone(),
        mlua::Error::CallbackError { cause, .. } => return unlocated(lua, cause),
        other => other.to_string(),
    };
    let line = message.lines().next().unwrap_or("").to_string();
    let prefix = format!("{}: ", caller_location(lua));
    line.strip_prefix(&prefix)
        .map(str::to_string)
        .unwrap_or(line)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::{Engine, SessionOptions};

    /// Runs `source` with a global `opts(t)` that parses tree options and returns the leaf
    /// texture source as text.
    fn run(dir: &std::path::Path, source: &str) -> pge_engine::Result<()> {
        let script = dir.join("t.lua");
        std::fs::write(&script, source).expect("write");
        let engine = Engine::builder().build().expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        let f = session
            .lua()
            .create_function(|lua, t: Table| {
                options_from_lua(lua, "tree", &t)
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
        std::fs::write(dir.path().join("leaf.png"), &png.png).expect("write png");
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
