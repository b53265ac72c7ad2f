//! The engine: plugins, limits and the library folder; it creates sessions.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use crate::files::{DiskFiles, Files};
use crate::{Error, Plugin, Result, Session, SessionOptions};

/// The limits every session of an engine runs under.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Bytes the Lua state may allocate.
    pub memory: usize,
    /// Wall-clock time of one generation (script and algorithm).
    pub time: Option<Duration>,
    /// Lua VM instructions one generation may execute.
    pub instructions: Option<u64>,
    /// Modules a rewriting system may hold at once.
    pub max_modules: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            memory: 4096 << 20,
            time: Some(Duration::from_secs(300)),
            instructions: None,
            max_modules: 10_000_000,
        }
    }
}

/// Where an engine's library folder comes from.
enum LibrarySource {
    None,
    Folder(PathBuf),
    Find(fn() -> Option<PathBuf>),
}

/// An engine's library folder, as given and canonical, resolved when first asked for (by
/// [`Engine::library`], or by a script that reads a file or requires a module): a run
/// whose scripts read nothing outside their own folder never looks for it. Shared by the
/// engine's clones, so every session of a process resolves it once.
struct Library {
    source: LibrarySource,
    folder: OnceLock<Option<(PathBuf, Option<PathBuf>)>>,
}

impl Library {
    fn resolved(&self, files: &dyn Files) -> Option<&(PathBuf, Option<PathBuf>)> {
        self.folder
            .get_or_init(|| {
                let folder = match &self.source {
                    LibrarySource::None => None,
                    LibrarySource::Folder(folder) => Some(folder.clone()),
                    LibrarySource::Find(find) => find(),
                }?;
                let canonical = files.canonicalize(&folder).ok();
                Some((folder, canonical))
            })
            .as_ref()
    }
}

/// Builds an [`Engine`]: plugins, limits, library folder, files.
pub struct EngineBuilder {
    plugins: Vec<Arc<dyn Plugin>>,
    limits: Limits,
    library: LibrarySource,
    files: Arc<dyn Files>,
}

impl Default for EngineBuilder {
    fn default() -> Self {
        EngineBuilder {
            plugins: Vec::new(),
            limits: Limits::default(),
            library: LibrarySource::None,
            files: Arc::new(DiskFiles),
        }
    }
}

impl EngineBuilder {
    /// Adds a plugin; its functions appear in the `pge` table of every session.
    #[must_use]
    pub fn plugin(mut self, plugin: impl Plugin) -> Self {
        self.plugins.push(Arc::new(plugin));
        self
    }

    /// The memory limit of each Lua state and of the plugins' buffers, in MiB (default
    /// 4096). At least 1 MiB: 0 counts as 1 (for Lua, 0 bytes would mean "unlimited").
    #[must_use]
    pub fn memory_limit_mib(mut self, mib: usize) -> Self {
        self.limits.memory = mib.max(1).saturating_mul(1 << 20);
        self
    }

    /// The time limit of one generation (default 300 s); `None` for no limit.
    #[must_use]
    pub fn time_limit(mut self, limit: Option<Duration>) -> Self {
        self.limits.time = limit;
        self
    }

    /// The instruction budget of one generation (default: none).
    #[must_use]
    pub fn instruction_limit(mut self, limit: Option<u64>) -> Self {
        self.limits.instructions = limit;
        self
    }

    /// The module-count cap of rewriting systems (default 10 000 000).
    #[must_use]
    pub fn max_modules(mut self, n: usize) -> Self {
        self.limits.max_modules = n;
        self
    }

    /// The engine's script library: `require` and `pge.load` may read it besides the
    /// script's own folder tree.
    #[must_use]
    pub fn library(mut self, folder: impl Into<PathBuf>) -> Self {
        self.library = LibrarySource::Folder(folder.into());
        self
    }

    /// The engine's script library, found by `find` when first needed (a script's
    /// `require` of a module, `pge.load` or a file it reads; [`Engine::library`]): the
    /// search costs a run whose scripts read nothing outside their folder nothing.
    #[must_use]
    pub fn library_found_by(mut self, find: fn() -> Option<PathBuf>) -> Self {
        self.library = LibrarySource::Find(find);
        self
    }

    /// Where sessions read scripts and the files scripts name (default: the file system).
    #[must_use]
    pub fn files(mut self, files: impl Files + 'static) -> Self {
        self.files = Arc::new(files);
        self
    }

    /// Builds the engine; two plugins with the same name are an error.
    pub fn build(self) -> Result<Engine> {
        for (i, p) in self.plugins.iter().enumerate() {
            if self.plugins[..i].iter().any(|q| q.name() == p.name()) {
                return Err(Error::DuplicatePlugin(p.name().to_string()));
            }
        }
        Ok(Engine {
            plugins: self.plugins,
            limits: self.limits,
            library: Arc::new(Library {
                source: self.library,
                folder: OnceLock::new(),
            }),
            files: self.files,
        })
    }
}

/// Owns the plugins and limits; creates [`Session`]s. Cheap to clone (the plugins are shared)
/// and to share between threads.
#[derive(Clone)]
pub struct Engine {
    plugins: Vec<Arc<dyn Plugin>>,
    limits: Limits,
    library: Arc<Library>,
    files: Arc<dyn Files>,
}

impl Engine {
    /// Starts building an engine.
    #[must_use]
    pub fn builder() -> EngineBuilder {
        EngineBuilder::default()
    }

    /// The limits sessions run under.
    #[must_use]
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// The library folder, if any (found now if the engine was built to find it).
    #[must_use]
    pub fn library(&self) -> Option<&Path> {
        self.library
            .resolved(&*self.files)
            .map(|(folder, _)| folder.as_path())
    }

    /// The library folder, canonical: `None` without one, or when it cannot be read.
    pub(crate) fn canonical_library(&self) -> Option<&Path> {
        self.library
            .resolved(&*self.files)
            .and_then(|(_, canonical)| canonical.as_deref())
    }

    /// Where sessions read scripts and the files scripts name.
    #[must_use]
    pub fn files(&self) -> &dyn Files {
        &*self.files
    }

    /// The plugins, in the order they were added.
    pub fn plugins(&self) -> impl Iterator<Item = &dyn Plugin> {
        self.plugins.iter().map(|p| &**p)
    }

    /// The plugins, shared (a session keeps those it registers lazily).
    pub(crate) fn shared_plugins(&self) -> &[Arc<dyn Plugin>] {
        &self.plugins
    }

    /// A new sandboxed Lua state with the support library and every plugin registered.
    pub fn session(&self, options: SessionOptions) -> Result<Session> {
        Session::new(self, options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Named(&'static str);
    impl Plugin for Named {
        fn name(&self) -> &str {
            self.0
        }
        fn register(&self, _: &mlua::Lua, _: &mlua::Table) -> mlua::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_library_to_find_is_looked_for_once_and_only_when_needed() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static SEARCHES: AtomicUsize = AtomicUsize::new(0);
        fn find() -> Option<PathBuf> {
            SEARCHES.fetch_add(1, Ordering::Relaxed);
            Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")))
        }
        let engine = Engine::builder()
            .library_found_by(find)
            .build()
            .expect("engine");
        let session = engine.session(SessionOptions::default()).expect("session");
        assert_eq!(session.eval::<i64>("return 1 + 1").expect("runs"), 2);
        assert_eq!(SEARCHES.load(Ordering::Relaxed), 0);
        let clone = engine.clone();
        assert_eq!(clone.library(), Some(Path::new(env!("CARGO_MANIFEST_DIR"))));
        assert!(engine.canonical_library().is_some());
        assert_eq!(SEARCHES.load(Ordering::Relaxed), 1);
    }

    #[test]
    fn duplicate_plugins_are_refused() {
        let err = Engine::builder()
            .plugin(Named("a"))
            .plugin(Named("a"))
            .build();
        assert!(matches!(err, Err(Error::DuplicatePlugin(n)) if n == "a"));
        assert!(
            Engine::builder()
                .plugin(Named("a"))
                .plugin(Named("b"))
                .build()
                .is_ok()
        );
    }
}
