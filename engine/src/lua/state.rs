//! Per-session state kept in the Lua state's app data.

use std::path::PathBuf;

use crate::{Charge, Location, RunContext};

/// A chunk the session loaded: the name errors show and the file behind it.
#[derive(Clone, Debug)]
pub(crate) struct Chunk {
    /// The path as shown to the user (`scripts/oak.lua`).
    pub display: String,
    /// The canonical file.
    pub path: PathBuf,
}

/// What the sandbox, the hook and the helpers share.
#[derive(Debug, Default)]
pub(crate) struct SessionState {
    pub ctx: RunContext,
    /// Canonical folders scripts may read from besides the engine's library folder: the
    /// folders of the main scripts run.
    pub roots: Vec<PathBuf>,
    /// The main script's folder (canonical), once a script runs.
    pub main_dir: Option<PathBuf>,
    /// The folder the output goes to (absolute), where scripts write their files.
    pub output_dir: Option<PathBuf>,
    pub chunks: Vec<Chunk>,
    /// Every file read: scripts, modules, meshes, textures (for live reload).
    pub loaded_files: Vec<PathBuf>,
    /// Where the Lua code was when the hook last ran (memory errors carry no position).
    pub last_location: Option<Location>,
    /// The Lua state's own use, charged to the run's budget (`ctx.budget`).
    pub lua_charge: Option<Charge>,
    pub instruction_limit: Option<u64>,
    pub instructions: u64,
}

impl SessionState {
    /// The chunk whose shown name is `display`, or whose shown name ends with the tail of a
    /// name Lua shortened to `...tail`.
    pub fn chunk(&self, display: &str) -> Option<&Chunk> {
        if let Some(tail) = display.strip_prefix("...") {
            self.chunks.iter().rev().find(|c| c.display.ends_with(tail))
        } else {
            self.chunks.iter().rev().find(|c| c.display == display)
        }
    }

    /// Charges the Lua state's use (`used` bytes) to the run's budget and returns what the
    /// state may hold now: the limit less what the rest of the run holds (other sessions'
    /// states, the buffers the run's work keeps); `None` when that is no more than `used`.
    pub fn sync_memory(&mut self, used: usize) -> Option<usize> {
        let budget = &self.ctx.budget;
        self.lua_charge
            .get_or_insert_with(|| budget.empty_charge())
            .set(used);
        let others = budget.used().saturating_sub(used);
        let room = budget.limit().saturating_sub(others);
        (room > used).then_some(room)
    }

    pub fn record_file(&mut self, path: PathBuf) {
        if !self.loaded_files.contains(&path) {
            self.loaded_files.push(path);
        }
    }
}

/// The engine that created the session, for the sandbox (its library folder). Plugins are
/// handed the engine by [`Plugin::register_in`](crate::Plugin::register_in), not from here.
pub(crate) struct EngineHandle(pub crate::Engine);

/// The engine's library folder (canonical), if any: found the first time a session of the
/// engine needs it.
pub(crate) fn library(lua: &mlua::Lua) -> Option<PathBuf> {
    lua.app_data_ref::<EngineHandle>()
        .and_then(|e| e.0.canonical_library().map(PathBuf::from))
}
