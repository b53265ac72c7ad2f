//! PGE, the procedural generation engine: this package is the `pge` command and the
//! batteries-included engine.
//!
//! [`generate`] is the one call a host makes: a script and `pge run`'s arguments in
//! ([`Request`]), the glb bytes `pge run` writes, its `--stats` and warnings out, errors
//! typed with their file and line ([`Error`]). Below it:
//!
//! [`default_engine`] returns an [`EngineBuilder`](pge_engine::EngineBuilder) with every
//! plugin of the project and the script library, so a host application generates a model
//! in a few lines:
//!
//! ```no_run
//! let engine = pge::default_engine().build()?;
//! let session = engine.session(Default::default())?;
//! let generated = session.generate("scripts/examples/spiral.lua".as_ref(), &mut |_, _| {})?;
//! let glb = pge_engine::export::glb_bytes(&generated.model, &Default::default())?;
//! std::fs::write("spiral.glb", glb)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

pub use pge_engine;

pub mod embed;

pub use embed::{
    Error, ErrorKind, Generation, Request, Script, Tile, VERSION, generate, params, tiles,
};

/// The file that marks a folder as PGE's script library (the repository's `scripts/`).
pub const LIBRARY_MARKER: &str = ".pge-library";

/// The folder of the script library, found at run time: `$PGE_LIBRARY` if set; else the
/// first folder named `scripts` holding a [`LIBRARY_MARKER`] file, looked for beside the
/// running program and in each folder above it (so `target/release/pge` of a checkout finds
/// the checkout's `scripts/`), then in the current folder and each folder above it. `None`
/// when there is none: scripts then read only their own folder tree.
///
/// A host that ships the library elsewhere passes its folder to
/// [`EngineBuilder::library`](pge_engine::EngineBuilder::library) instead.
#[must_use]
pub fn library_folder() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("PGE_LIBRARY").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    let exe = std::env::current_exe().ok();
    let cwd = std::env::current_dir().ok();
    exe.as_deref()
        .and_then(Path::parent)
        .and_then(find_library)
        .or_else(|| cwd.as_deref().and_then(find_library))
}

/// The first `scripts` folder with the marker in `start` or a folder above it.
fn find_library(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .map(|dir| dir.join("scripts"))
        .find(|candidate| candidate.join(LIBRARY_MARKER).is_file())
}

/// An engine builder with every PGE plugin and the script library ([`library_folder`],
/// looked for when a script first needs it).
#[must_use]
pub fn default_engine() -> pge_engine::EngineBuilder {
    engine_with_forest(pge_forest::ForestPlugin::default())
}

/// [`default_engine`] with `forest` as its forest plugin (one with a variant cache, for
/// `pge run --variant-cache`).
#[must_use]
pub fn engine_with_forest(forest: pge_forest::ForestPlugin) -> pge_engine::EngineBuilder {
    pge_plugins::with_all(
        pge_engine::Engine::builder().library_found_by(library_folder),
        forest,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_is_the_marked_scripts_folder_above_a_start() {
        let dir = tempfile::tempdir().expect("tempdir");
        let deep = dir.path().join("target/release/deps");
        std::fs::create_dir_all(&deep).expect("folders");
        std::fs::create_dir_all(dir.path().join("target/scripts")).expect("unmarked");
        assert_eq!(find_library(&deep), None);
        std::fs::create_dir_all(dir.path().join("scripts")).expect("library");
        std::fs::write(dir.path().join("scripts").join(LIBRARY_MARKER), "").expect("marker");
        assert_eq!(find_library(&deep), Some(dir.path().join("scripts")));
    }

    #[test]
    fn a_lazy_plugin_sets_exactly_its_names_and_no_two_plugins_share_one() {
        let engine = default_engine().build().expect("engine");
        let mut seen: Vec<&str> = Vec::new();
        for plugin in engine.plugins() {
            let mut names: Vec<&str> = plugin.lazy_names().to_vec();
            if names.is_empty() {
                continue;
            }
            let lua = pge_engine::mlua::Lua::new();
            let pge = lua.create_table().expect("table");
            plugin.register(&lua, &pge).expect("registers");
            let mut set: Vec<String> = pge
                .pairs::<String, pge_engine::mlua::Value>()
                .map(|kv| kv.expect("string keys").0)
                .collect();
            set.sort();
            names.sort_unstable();
            assert_eq!(set, names, "{}", plugin.name());
            assert!(!names.iter().any(|n| seen.contains(n)), "{}", plugin.name());
            seen.extend(names);
        }
        assert!(seen.contains(&"SpaceColonization"), "{seen:?}");
    }

    #[test]
    fn this_checkout_has_a_marked_library() {
        let scripts = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
        assert!(scripts.join(LIBRARY_MARKER).is_file());
    }
}
