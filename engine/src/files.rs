//! Where sessions read scripts, modules and the files scripts name (meshes, images): the file
//! system ([`DiskFiles`], the default), or files held in memory ([`MemoryFiles`]: a browser,
//! where the library comes bundled and the script from an editor). An engine is given one
//! with [`EngineBuilder::files`](crate::EngineBuilder::files).

use std::collections::BTreeMap;
use std::io;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// A read-only file tree with canonical (absolute, normalised) paths.
pub trait Files: Send + Sync {
    /// `path` absolute (a relative one is taken from the working folder), `.` and `..`
    /// resolved (and links, where there are any); an error when nothing is there.
    fn canonicalize(&self, path: &Path) -> io::Result<PathBuf>;
    /// Whether the canonical `path` is a file (not a folder).
    fn is_file(&self, path: &Path) -> bool;
    /// The bytes of the file at the canonical `path`.
    fn read(&self, path: &Path) -> io::Result<Vec<u8>>;
    /// The working folder, canonical: paths inside it are shown relative to it
    /// (`scripts/species/oak.lua:9:`).
    fn working_folder(&self) -> Option<PathBuf>;
    /// Whether scripts may write files (`img:save`) on the file system: only when they read
    /// from it.
    fn writable(&self) -> bool {
        false
    }
}

/// The file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct DiskFiles;

impl Files for DiskFiles {
    fn canonicalize(&self, path: &Path) -> io::Result<PathBuf> {
        path.canonicalize()
    }

    fn is_file(&self, path: &Path) -> bool {
        path.is_file()
    }

    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        std::fs::read(path)
    }

    fn working_folder(&self) -> Option<PathBuf> {
        std::env::current_dir().ok()?.canonicalize().ok()
    }

    fn writable(&self) -> bool {
        true
    }
}

/// Files in memory under absolute paths; the folders are those the files lie in, and the
/// working folder is the root (`/`).
#[derive(Clone, Debug, Default)]
pub struct MemoryFiles {
    files: BTreeMap<PathBuf, Arc<[u8]>>,
}

impl MemoryFiles {
    /// No files.
    #[must_use]
    pub fn new() -> MemoryFiles {
        MemoryFiles::default()
    }

    /// Adds (or replaces) the file at `path` (taken from the root when relative).
    pub fn insert(&mut self, path: impl AsRef<Path>, bytes: impl Into<Arc<[u8]>>) {
        self.files.insert(absolute(path.as_ref()), bytes.into());
    }

    /// The files' paths, in order.
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.files.keys().map(PathBuf::as_path)
    }

    fn is_folder(&self, path: &Path) -> bool {
        self.files
            .range(path.to_path_buf()..)
            .next()
            .is_some_and(|(k, _)| k != path && k.starts_with(path))
    }
}

/// `path` from the root, `.` and `..` resolved lexically (`..` at the root stays there).
fn absolute(path: &Path) -> PathBuf {
    let mut out = PathBuf::from("/");
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::Normal(name) => out.push(name),
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
        }
    }
    out
}

fn not_found(path: &Path) -> io::Error {
    io::Error::new(
        io::ErrorKind::NotFound,
        format!("no such file: {}", path.display()),
    )
}

impl Files for MemoryFiles {
    fn canonicalize(&self, path: &Path) -> io::Result<PathBuf> {
        let p = absolute(path);
        if self.files.contains_key(&p) || p == Path::new("/") || self.is_folder(&p) {
            Ok(p)
        } else {
            Err(not_found(path))
        }
    }

    fn is_file(&self, path: &Path) -> bool {
        self.files.contains_key(path)
    }

    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        self.files
            .get(path)
            .map(|b| b.to_vec())
            .ok_or_else(|| not_found(path))
    }

    fn working_folder(&self) -> Option<PathBuf> {
        Some(PathBuf::from("/"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_files_resolve_relative_paths_and_folders() {
        let mut files = MemoryFiles::new();
        files.insert("scripts/species/oak.lua", &b"return 1"[..]);
        files.insert("/scripts/species.lua", &b"return 2"[..]);
        let oak = files
            .canonicalize(Path::new("scripts/forests/../species/./oak.lua"))
            .expect("found");
        assert_eq!(oak, Path::new("/scripts/species/oak.lua"));
        assert!(files.is_file(&oak));
        assert_eq!(files.read(&oak).expect("read"), b"return 1");
        let folder = files
            .canonicalize(Path::new("/scripts/species"))
            .expect("a folder");
        assert!(!files.is_file(&folder));
        assert!(files.read(&folder).is_err());
        assert!(files.canonicalize(Path::new("/scripts/spec")).is_err());
        assert!(files.canonicalize(Path::new("scripts/pine.lua")).is_err());
        assert_eq!(
            files
                .canonicalize(Path::new("../../scripts"))
                .expect("root"),
            Path::new("/scripts")
        );
        assert_eq!(files.working_folder(), Some(PathBuf::from("/")));
        assert_eq!(files.paths().count(), 2);
        assert!(!files.writable() && DiskFiles.writable());
    }
}
