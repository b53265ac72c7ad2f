//! Sessions: one sandboxed Lua state in which scripts run.

use crate::clock::Instant;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use mlua::{FromLuaMulti, HookTriggers, Lua, LuaOptions, StdLib, Value, VmState};

use crate::algorithm::run;
use crate::geometry::Model;
use crate::lua::params::{self, ParamInfo, ParamState};
use crate::lua::random::CurrentRng;
use crate::lua::state::SessionState;
use crate::lua::to_engine_error;
use crate::{Algorithm, Budget, Engine, Error, Limits, Location, Result, RunContext};

/// How often (in VM instructions) the hook checks the limits.
const HOOK_INTERVAL: u32 = 4096;

/// What a session is created with.
#[derive(Clone, Debug)]
pub struct SessionOptions {
    /// The run's seed (`--seed`, default 1).
    pub seed: u64,
    /// `--set NAME=VALUE` overrides of the main script's declared parameters.
    pub params: Vec<(String, String)>,
    /// `--steps`: how many steps to run, overriding the algorithm's own count.
    pub steps: Option<u32>,
    /// Set from another thread to stop the run (checked by the Lua hook and by algorithms).
    pub cancel: Option<Arc<AtomicBool>>,
    /// The deadline of the run this session is part of (a forest's variant grown in a
    /// session of its own): `None` starts the clock of `--time-limit` when the script starts.
    pub deadline: Option<Instant>,
    /// The memory budget of the run this session is part of, which its Lua state and its
    /// work charge too: `None` for a budget of its own, of the engine's memory limit.
    pub budget: Option<Budget>,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            seed: 1,
            params: Vec::new(),
            steps: None,
            cancel: None,
            deadline: None,
            budget: None,
        }
    }
}

/// The outcome of [`Session::generate`].
#[derive(Debug)]
pub struct Generated {
    /// The model.
    pub model: Model,
    /// The main script's declared parameters with the values used.
    pub params: Vec<ParamInfo>,
    /// Wall-clock seconds of the whole generation.
    pub seconds: f64,
}

/// How [`Started::grow`] grows a script's value.
#[derive(Clone, Copy, Debug, Default)]
#[non_exhaustive]
pub struct GrowOptions {
    /// An empty model is expected (a forest that writes only its shared variants places
    /// nothing): no warning for it.
    pub empty_expected: bool,
}

impl GrowOptions {
    /// No warning for an empty model.
    #[must_use]
    pub fn empty_expected(mut self) -> Self {
        self.empty_expected = true;
        self
    }
}

/// A main script that has run, its value not grown yet ([`Session::start`]).
pub struct Started<'s> {
    session: &'s Session,
    path: PathBuf,
    value: Value,
    t0: Instant,
    script_seconds: f64,
}

impl Started<'_> {
    /// The value the script returned.
    #[must_use]
    pub fn value(&self) -> &Value {
        &self.value
    }

    /// The algorithm of the value, to step by hand (growth stages).
    pub fn algorithm(self) -> Result<Box<dyn Algorithm>> {
        self.session.algorithm_from(self.value)
    }

    /// Runs the value's algorithm to the end (or `--steps`) and returns the model, the
    /// script's time as its first phase. `progress` receives (steps taken, steps planned if
    /// known).
    pub fn grow(
        self,
        options: GrowOptions,
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> Result<Generated> {
        self.grow_with(options, |_| Ok::<(), Error>(()), progress)
    }

    /// As [`Started::grow`], with `prepare` seeing the algorithm before it runs: a host
    /// reaches the concrete type through [`Algorithm::as_any_mut`] (a forest whose tile it
    /// picks) or refuses the value with an error of its own.
    pub fn grow_with<E: From<Error>>(
        self,
        options: GrowOptions,
        prepare: impl FnOnce(&mut dyn Algorithm) -> std::result::Result<(), E>,
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> std::result::Result<Generated, E> {
        let session = self.session;
        let mut algorithm = session.algorithm_from(self.value)?;
        prepare(&mut *algorithm)?;
        let ctx = session.context();
        let planned = ctx.steps.or(algorithm.planned_steps());
        let mut model = run(&mut *algorithm, &ctx, &mut |s| progress(s, planned))?;
        model
            .stats
            .phases
            .insert(0, ("script".into(), self.script_seconds));
        if !options.empty_expected {
            model.warn_if_empty(&self.path);
        }
        Ok(Generated {
            model,
            params: session.declared_params(),
            seconds: self.t0.elapsed().as_secs_f64(),
        })
    }
}

/// One sandboxed Lua 5.4 state with the support library and the engine's plugins.
///
/// The standard library has no `io`, `os`, `debug` or `package`; `require` and `pge.load`
/// read only the main script's folder tree and the engine's library folder; memory, time and
/// instructions are limited. A session is not `Send`: create one per thread.
pub struct Session {
    lua: Lua,
    limits: Limits,
    overrides: Vec<(String, String)>,
    script: std::cell::RefCell<Option<String>>,
}

impl Session {
    pub(crate) fn new(engine: &Engine, options: SessionOptions) -> Result<Session> {
        let limits = engine.limits().clone();
        let libs = StdLib::TABLE | StdLib::STRING | StdLib::MATH | StdLib::UTF8 | StdLib::COROUTINE;
        let lua = Lua::new_with(libs, LuaOptions::default()).map_err(|e| Error::Plugin {
            plugin: "lua".into(),
            message: e.to_string(),
        })?;
        // What a session sets up is all kept: no garbage to collect until the script runs.
        lua.gc_stop();
        let budget = options
            .budget
            .clone()
            .unwrap_or_else(|| Budget::new(limits.memory));
        lua.set_memory_limit(budget.available().max(1))
            .map_err(|e| Error::Plugin {
                plugin: "lua".into(),
                message: e.to_string(),
            })?;
        lua.set_app_data(SessionState {
            ctx: RunContext {
                seed: options.seed,
                steps: options.steps,
                deadline: options.deadline,
                max_modules: limits.max_modules,
                cancel: options.cancel.clone(),
                budget,
            },
            instruction_limit: limits.instructions,
            ..SessionState::default()
        });
        lua.set_app_data(crate::lua::state::EngineHandle(engine.clone()));
        lua.set_app_data(CurrentRng::from_seed(options.seed));
        // The registry of session services the plugins fill while they register.
        lua.set_app_data(crate::lua::services::Services::default());
        install_hook(&lua).map_err(|e| Error::Plugin {
            plugin: "lua".into(),
            message: e.to_string(),
        })?;
        let setup = |lua: &Lua| -> mlua::Result<mlua::Table> {
            let pge = lua.create_table()?;
            crate::lua::register_support(lua, &pge)?;
            lua.globals().set("pge", pge.clone())?;
            Ok(pge)
        };
        let pge = setup(&lua).map_err(|e| Error::Plugin {
            plugin: "pge".into(),
            message: e.to_string(),
        })?;
        let mut lazy = Vec::new();
        for plugin in engine.shared_plugins() {
            if !plugin.lazy_names().is_empty() {
                lazy.push(plugin.clone());
                continue;
            }
            plugin
                .register_in(engine, &lua, &pge)
                .map_err(|e| Error::Plugin {
                    plugin: plugin.name().to_string(),
                    message: e.to_string(),
                })?;
        }
        crate::lua::register_lazily(&lua, &pge, engine, lazy).map_err(|e| Error::Plugin {
            plugin: "pge".into(),
            message: e.to_string(),
        })?;
        lua.gc_restart();
        if let Err(e) = sync_memory(&lua) {
            return Err(e.at(Location {
                file: "pge".into(),
                line: None,
            }));
        }
        Ok(Session {
            lua,
            limits,
            overrides: options.params,
            script: std::cell::RefCell::new(None),
        })
    }

    /// The Lua state, for plugins and hosts that bind more.
    #[must_use]
    pub fn lua(&self) -> &Lua {
        &self.lua
    }

    /// The run context (seed, steps, deadline, module cap) algorithms receive.
    #[must_use]
    pub fn context(&self) -> RunContext {
        crate::lua::run_context(&self.lua)
    }

    /// Evaluates a snippet of Lua (named `eval` in errors).
    pub fn eval<T: FromLuaMulti>(&self, code: &str) -> Result<T> {
        self.start_clock();
        self.lua
            .load(code)
            .set_name("=eval")
            .eval()
            .map_err(|e| to_engine_error(&self.lua, e))
    }

    /// Evaluates a snippet of Lua and returns its first value.
    pub fn eval_value(&self, code: &str) -> Result<Value> {
        self.eval(code)
    }

    fn start_clock(&self) {
        if let Some(mut st) = self.lua.app_data_mut::<SessionState>()
            && st.ctx.deadline.is_none()
        {
            st.ctx.deadline = self.limits.time.map(|t| Instant::now() + t);
        }
    }

    /// The folder the run's output goes to: files a script writes (`img:save`) go there
    /// instead of the main script's folder (it is created when a script first writes, and
    /// only then resolved: most scripts write nothing).
    pub fn set_output_folder(&self, dir: &Path) -> Result<()> {
        let absolute = std::env::current_dir()
            .map(|cwd| cwd.join(dir))
            .map_err(|e| Error::Plugin {
                plugin: "output".into(),
                message: format!("{}: {e}", dir.display()),
            })?;
        if let Some(mut st) = self.lua.app_data_mut::<SessionState>() {
            st.output_dir = Some(absolute);
        }
        Ok(())
    }

    /// Runs the main script and returns its value. The script's folder becomes readable by
    /// `require` and `pge.load`; a `--set` override it does not declare is an error.
    pub fn run_script(&self, path: &Path) -> Result<Value> {
        let shown = path.to_string_lossy().replace('\\', "/");
        let canonical = crate::lua::with_files(&self.lua, |files| files.canonicalize(path));
        let canonical = canonical.map_err(|e| {
            Error::script(
                Location {
                    file: shown.clone(),
                    line: None,
                },
                format!("cannot read script: {e}"),
            )
        })?;
        if !crate::lua::with_files(&self.lua, |files| files.is_file(&canonical)) {
            return Err(Error::script(
                Location {
                    file: shown,
                    line: None,
                },
                "cannot read script: not a file",
            ));
        }
        self.run_main(shown, canonical, None)
    }

    /// Runs `source` as the main script, as [`Session::run_script`] runs a file: `name` is
    /// the file it is shown as in errors (`name:LINE: message`), and the folder of `name`
    /// (relative to the current folder), when it exists, is the script's folder for
    /// `require` and `pge.load`; otherwise the script reads only the library. For a host
    /// that holds a script's text (an editor's unsaved buffer).
    pub fn run_source(&self, name: &str, source: &str) -> Result<Value> {
        let shown = name.replace('\\', "/");
        let file = Path::new(name).file_name().unwrap_or_default();
        let dir = match Path::new(name).parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let canonical = match dir.canonicalize() {
            Ok(dir) if dir.is_dir() => dir.join(file),
            _ => PathBuf::from(file),
        };
        self.run_main(shown, canonical, Some(source.to_string()))
    }

    /// Runs the main script `canonical` (its text `source`, or the file's), shown as `shown`.
    fn run_main(&self, shown: String, canonical: PathBuf, source: Option<String>) -> Result<Value> {
        *self.script.borrow_mut() = Some(shown.clone());
        if let Some(mut st) = self.lua.app_data_mut::<SessionState>() {
            let dir = canonical.parent().map(Path::to_path_buf);
            if let Some(dir) = dir.filter(|d| d.is_absolute()) {
                st.roots.insert(0, dir.clone());
                st.main_dir = Some(dir);
            }
        }
        params::begin_main(&self.lua, &shown, &self.overrides);
        self.start_clock();
        let value = match source {
            Some(text) => crate::lua::sandbox_exec_source(&self.lua, shown, canonical, text),
            None => crate::lua::sandbox_exec(&self.lua, shown, canonical),
        }
        .map_err(|e| to_engine_error(&self.lua, e))?;
        params::end_main(&self.lua)
            .map_err(|(location, message)| Error::script(location, message))?;
        Ok(value)
    }

    /// Turns a script's value into an algorithm (see [`crate::lua::algorithm_from`]).
    pub fn algorithm_from(&self, value: Value) -> Result<Box<dyn Algorithm>> {
        let location = Location {
            file: self
                .script
                .borrow()
                .clone()
                .unwrap_or_else(|| "eval".into()),
            line: None,
        };
        crate::lua::algorithm_from(&self.lua, value, &location)
    }

    /// Runs the script, then its algorithm to the end (or `--steps`), and returns the model.
    /// `progress` receives (steps taken, steps planned if known). The same as
    /// [`Session::start`] then [`Started::grow`].
    pub fn generate(
        &self,
        path: &Path,
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> Result<Generated> {
        self.start(path)?.grow(GrowOptions::default(), progress)
    }

    /// Runs the main script ([`Session::run_script`]) and holds its value, not grown yet: the
    /// host looks at it or configures it ([`Started::value`]) before it grows.
    pub fn start(&self, path: &Path) -> Result<Started<'_>> {
        let t0 = Instant::now();
        let value = self.run_script(path)?;
        Ok(Started {
            session: self,
            path: path.to_path_buf(),
            value,
            t0,
            script_seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// [`Session::start`] for a main script given as text ([`Session::run_source`]).
    pub fn start_source(&self, name: &str, source: &str) -> Result<Started<'_>> {
        let t0 = Instant::now();
        let value = self.run_source(name, source)?;
        Ok(Started {
            session: self,
            path: PathBuf::from(name),
            value,
            t0,
            script_seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The main script's declared parameters, once it has run.
    #[must_use]
    pub fn declared_params(&self) -> Vec<ParamInfo> {
        self.lua
            .app_data_ref::<ParamState>()
            .map(|p| p.main.clone())
            .unwrap_or_default()
    }

    /// Every file the session read: scripts, modules, meshes, textures.
    #[must_use]
    pub fn loaded_files(&self) -> Vec<PathBuf> {
        self.lua
            .app_data_ref::<SessionState>()
            .map(|s| s.loaded_files.clone())
            .unwrap_or_default()
    }
}

/// Charges the Lua state's use to the run's budget and lets it hold what the budget has
/// left; an [`Error::MemoryLimit`] (placed nowhere yet) when nothing is left.
fn sync_memory(lua: &Lua) -> Result<()> {
    let used = lua.used_memory();
    let Some(mut st) = lua.app_data_mut::<SessionState>() else {
        return Ok(());
    };
    match st.sync_memory(used) {
        Some(room) => {
            lua.set_memory_limit(room).map_err(|e| Error::Plugin {
                plugin: "lua".into(),
                message: e.to_string(),
            })?;
            Ok(())
        }
        None => Err(st.ctx.budget.exceeded(&Location::default(), None)),
    }
}

/// The hook that enforces the time and instruction limits, keeps the Lua state's memory in
/// the run's budget (other sessions of the run and the buffers of its work leave it less
/// room) and remembers where the script is (memory errors carry no position).
fn install_hook(lua: &Lua) -> mlua::Result<()> {
    let triggers = HookTriggers::new().every_nth_instruction(HOOK_INTERVAL);
    lua.set_global_hook(triggers, |lua, debug| {
        let Some(mut st) = lua.app_data_mut::<SessionState>() else {
            return Ok(VmState::Continue);
        };
        st.instructions += HOOK_INTERVAL as u64;
        // Remember where the script is, allocating only when it moved to another chunk.
        let line = debug.current_line().map(|l| l as u32);
        {
            let source = debug.source();
            let name = source.source.as_deref().unwrap_or("?");
            let file = name
                .strip_prefix('@')
                .or_else(|| name.strip_prefix('='))
                .unwrap_or(name);
            match &mut st.last_location {
                Some(loc) if loc.file == file => loc.line = line,
                other => {
                    *other = Some(Location {
                        file: file.to_string(),
                        line,
                    })
                }
            }
        }
        let used = lua.used_memory();
        let room = st.sync_memory(used);
        let here = || st.last_location.clone().unwrap_or_default();
        if let Some(room) = room {
            lua.set_memory_limit(room)?;
        }
        let limit = if room.is_none() {
            Some(st.ctx.budget.exceeded(&here(), None))
        } else if st
            .ctx
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
            || st.ctx.budget.stopped()
        {
            Some(Error::Cancelled { location: here() })
        } else if st.ctx.deadline.is_some_and(|d| Instant::now() >= d) {
            Some(Error::TimeLimit { location: here() })
        } else {
            match st.instruction_limit {
                Some(limit) if st.instructions > limit => Some(Error::InstructionLimit {
                    location: here(),
                    limit,
                }),
                _ => None,
            }
        };
        match limit {
            Some(e) => Err(mlua::Error::external(e)),
            None => Ok(VmState::Continue),
        }
    })?;
    Ok(())
}
