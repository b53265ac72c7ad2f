//! Watching the script and the files it loaded.
//!
//! The folders holding the files are watched rather than the files: editors often save by
//! writing a new file and renaming it over the old one, and a deleted script must be noticed
//! when it comes back. Events are filtered to changes of content or presence and passed on as
//! [`watch_key`] paths, which is how the reloader names watched files.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;

use notify::event::{MetadataKind, ModifyKind};
use notify::{EventKind, RecommendedWatcher, RecursiveMode, Watcher as _};

/// The name under which a file is watched: its folder canonicalised, then its file name
/// (so the file itself may be missing, and the key matches the paths of watcher events).
#[must_use]
pub fn watch_key(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => dir.canonicalize().map(|d| d.join(name)).unwrap_or(abs),
        _ => abs,
    }
}

/// Watches the folders of a set of files and sends the paths of changed files.
pub struct Watcher {
    inner: RecommendedWatcher,
    folders: BTreeSet<PathBuf>,
}

impl Watcher {
    /// A watcher sending every batch of changed paths to `events`, then calling `wake`.
    pub fn new(
        events: Sender<Vec<PathBuf>>,
        wake: impl Fn() + Send + 'static,
    ) -> notify::Result<Watcher> {
        let inner = notify::recommended_watcher(move |event: notify::Result<notify::Event>| {
            let Ok(event) = event else { return };
            if is_change(&event.kind) && events.send(event.paths).is_ok() {
                wake();
            }
        })?;
        Ok(Watcher {
            inner,
            folders: BTreeSet::new(),
        })
    }

    /// Watches the folders of `files` (keys from [`watch_key`]) and no others.
    pub fn watch_files<'a>(
        &mut self,
        files: impl IntoIterator<Item = &'a PathBuf>,
    ) -> notify::Result<()> {
        let wanted: BTreeSet<PathBuf> = files
            .into_iter()
            .filter_map(|f| f.parent().map(Path::to_path_buf))
            .collect();
        for gone in self.folders.difference(&wanted) {
            // A folder that was deleted is no longer watched anyway.
            let _ = self.inner.unwatch(gone);
        }
        let mut result = Ok(());
        let mut watching = BTreeSet::new();
        for folder in wanted {
            if self.folders.contains(&folder) {
                watching.insert(folder);
                continue;
            }
            match self.inner.watch(&folder, RecursiveMode::NonRecursive) {
                Ok(()) => {
                    watching.insert(folder);
                }
                Err(e) => result = Err(e),
            }
        }
        self.folders = watching;
        result
    }
}

/// Whether an event changes a file's content or presence (not reads, not access times).
fn is_change(kind: &EventKind) -> bool {
    match kind {
        EventKind::Create(_) | EventKind::Remove(_) => true,
        EventKind::Modify(ModifyKind::Metadata(MetadataKind::AccessTime)) => false,
        EventKind::Modify(_) => true,
        EventKind::Access(_) | EventKind::Any | EventKind::Other => false,
    }
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc::channel;
    use std::time::{Duration, Instant};

    use super::*;

    fn wait_for(rx: &std::sync::mpsc::Receiver<Vec<PathBuf>>, key: &Path) -> bool {
        let end = Instant::now() + Duration::from_secs(10);
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            match rx.recv_timeout(left) {
                Ok(paths) if paths.iter().any(|p| p == key) => return true,
                Ok(_) => {}
                Err(_) => return false,
            }
        }
        false
    }

    #[test]
    fn keys_of_missing_files_match_existing_ones() {
        let dir = tempfile::tempdir().expect("tempdir");
        let file = dir.path().join("a.lua");
        let before = watch_key(&file);
        std::fs::write(&file, "x").expect("write");
        assert_eq!(before, watch_key(&file));
        assert_eq!(before, file.canonicalize().expect("exists"));
    }

    #[test]
    fn writes_deletions_and_recreations_are_seen() {
        let dir = tempfile::tempdir().expect("tempdir");
        let file = dir.path().join("tree.lua");
        std::fs::write(&file, "return 1").expect("write");
        let key = watch_key(&file);
        let (tx, rx) = channel();
        let mut watcher = Watcher::new(tx, || {}).expect("watcher");
        watcher.watch_files([&key]).expect("watch");
        std::fs::write(&file, "return 2").expect("write");
        assert!(wait_for(&rx, &key), "write seen");
        std::fs::remove_file(&file).expect("remove");
        assert!(wait_for(&rx, &key), "removal seen");
        // An editor's save by rename.
        let tmp = dir.path().join(".tree.lua.swp");
        std::fs::write(&tmp, "return 3").expect("write");
        std::fs::rename(&tmp, &file).expect("rename");
        assert!(wait_for(&rx, &key), "recreation seen");
    }
}
