//! Writing a model to disk, shared by `pge run` and the preview's export: `.glb`, or `.obj`
//! with its `.mtl` and textures next to it, every file written atomically.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use pge_engine::ParamInfo;
use pge_engine::export::{ExportMeta, Instancing, obj_files, write_glb_with};
use pge_engine::geometry::Model;

/// The metadata a `.glb` records: the seed and the parameters' values, in order.
#[must_use]
pub fn export_meta(seed: u64, params: &[ParamInfo]) -> ExportMeta {
    ExportMeta {
        seed,
        params: params
            .iter()
            .map(|p| (p.name.clone(), p.value.to_json()))
            .collect(),
    }
}

/// Writes `bytes` to `path` atomically, as [`write_atomically_with`] does.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    write_atomically_with(path, |file| file.write_all(bytes))
}

/// Writes a file at `path` with `write` through a temporary file in the same folder, which
/// then takes `path`'s place, so that a failure never leaves a half-written file. The file
/// gets the permissions of any new file (`0666` less the umask), not the temporary file's
/// private `0600`.
pub fn write_atomically_with(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> anyhow::Result<()> {
    let mut file = AtomicFile::create(path)?;
    write(file.tmp.as_file_mut()).with_context(|| format!("cannot write {}", path.display()))?;
    file.finish()
}

/// A file being written at `path` as [`write_atomically_with`] does: its temporary file,
/// created before the bytes are ready (a `.glb` is built meanwhile).
struct AtomicFile<'a> {
    tmp: tempfile::NamedTempFile,
    path: &'a Path,
}

/// The pages of a `.glb` output's next version, made ahead of it on another thread: an
/// unnamed temporary file in the output's folder (Linux's `O_TMPFILE`, so nothing is left
/// behind should the run fail or be stopped), as long as the file it will replace, its
/// pages already allocated. Writing 2.5 MB into tmpfs is half page allocation and memory
/// cgroup charges, the other half the copy: made here, beside the session and the growth,
/// the allocation is off the run's path, and the write only copies. Only on tmpfs: a disk
/// file system allocates blocks for a reserved file at once, and the next run then frees
/// them when it replaces the file (a 2.5 MB file on ext4: 4 ms instead of 0.5, see the
/// oakexport section of benches/README.md), where a written one has none yet.
pub struct Reserved {
    file: std::fs::File,
    len: u64,
}

/// The most bytes [`reserve`] reserves: a new file much smaller than the old one gives back
/// the pages reserved past its end when it is cut to its length, on the run's path.
const RESERVE_AT_MOST: u64 = 64 << 20;

/// [`Reserved`] pages for the next version of `path`, as many as it has (at most
/// [`RESERVE_AT_MOST`]), when it is a regular file on tmpfs (`tmpfs_only`; any file system
/// otherwise) that is not empty; `None` when there is nothing to reserve or the file system
/// cannot make an unnamed file or reserve.
#[must_use]
pub fn reserve(path: &Path, tmpfs_only: bool) -> Option<Reserved> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, FallocateFlags, Mode, OFlags, fallocate, openat, statfs};
        /// `statfs`'s `f_type` of tmpfs.
        const TMPFS_MAGIC: u64 = 0x0102_1994;
        let old = std::fs::symlink_metadata(path).ok()?;
        if !old.is_file() || old.len() == 0 {
            return None;
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if tmpfs_only && statfs(dir).ok()?.f_type as u64 != TMPFS_MAGIC {
            return None;
        }
        // The mode of any new file, as the temporary file made at the export has.
        let flags = OFlags::TMPFILE | OFlags::RDWR | OFlags::CLOEXEC;
        let fd = openat(CWD, dir, flags, Mode::from_raw_mode(0o666)).ok()?;
        // At most [`RESERVE_AT_MOST`]: a much smaller new file is cut back on the run's path.
        let len = old.len().min(RESERVE_AT_MOST);
        fallocate(&fd, FallocateFlags::empty(), 0, len).ok()?;
        Some(Reserved {
            file: std::fs::File::from(fd),
            len,
        })
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (path, tmpfs_only);
        None
    }
}

impl<'a> AtomicFile<'a> {
    /// The temporary file for `path`, in the same folder.
    fn create(path: &'a Path) -> anyhow::Result<AtomicFile<'a>> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let mut builder = tempfile::Builder::new();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            // The kernel applies the umask to the mode given at creation.
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder
            .tempfile_in(&dir)
            .with_context(|| format!("cannot write in {}", dir.display()))?;
        Ok(AtomicFile { tmp, path })
    }

    /// The temporary file for `path` made of `reserved`: linked into `path`'s folder under
    /// a temporary name (through `/proc/self/fd`, as an unprivileged process links an
    /// unnamed file), so that it is written and put in place as [`AtomicFile::create`]'s.
    #[cfg(target_os = "linux")]
    fn from_reserved(path: &'a Path, reserved: Reserved) -> std::io::Result<AtomicFile<'a>> {
        use std::os::fd::AsRawFd;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let unnamed = format!("/proc/self/fd/{}", reserved.file.as_raw_fd());
        let mut file = Some(reserved.file);
        let tmp = tempfile::Builder::new().make_in(dir, |name| {
            use rustix::fs::{AtFlags, CWD, linkat};
            linkat(CWD, unnamed.as_str(), CWD, name, AtFlags::SYMLINK_FOLLOW)?;
            file.take()
                .ok_or_else(|| std::io::Error::other("the reserved file is linked already"))
        })?;
        Ok(AtomicFile { tmp, path })
    }

    #[cfg(not(target_os = "linux"))]
    fn from_reserved(_: &'a Path, _: Reserved) -> std::io::Result<AtomicFile<'a>> {
        Err(std::io::ErrorKind::Unsupported.into())
    }

    /// Puts the written temporary file in `path`'s place.
    fn finish(self) -> anyhow::Result<()> {
        let AtomicFile { tmp, path } = self;
        if let Some(old) = exchanged(&tmp, path) {
            // The temporary name now holds the old file, which dropping `tmp` unlinks; as
            // `old` still holds it, its pages and blocks are freed only when `old` is closed
            // (10-25 ms for a 64 MB file, 0.3-0.5 ms for 2.5 MB), off the caller's thread
            // when it can be.
            drop(tmp);
            close_aside(old);
            return Ok(());
        }
        tmp.persist(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(())
    }
}

/// Closes `file` on the rayon pool when it has more than one thread (the caller goes on at
/// once), on the calling thread otherwise. Should the process end first, the kernel closes
/// it on the way out.
fn close_aside(file: std::fs::File) {
    if rayon::current_num_threads() > 1 {
        rayon::spawn(move || drop(file));
    } else {
        drop(file);
    }
}

/// The old file, still open (`O_PATH`: no permission needed), when the finished temporary
/// file `tmp` and an existing regular file at `path` were swapped in one step (Linux's
/// `renameat2` with `RENAME_EXCHANGE`): `path` is the old file or the new one at every
/// moment, as with a rename. A rename over an existing file would make ext4 allocate and
/// start writing the new file's blocks before it returns (its `auto_da_alloc` guard against
/// files emptied by a crash): 2-5 ms for a 2.5 MB tree, tens of milliseconds for a 40 MB
/// one, against 0.2 ms for the exchange. `None` when there is no such file or the file
/// system cannot swap (the caller renames then).
#[cfg(target_os = "linux")]
fn exchanged(tmp: &tempfile::NamedTempFile, path: &Path) -> Option<std::fs::File> {
    use rustix::fs::{CWD, FileType, Mode, OFlags, RenameFlags, fstat, open, renameat_with};
    let flags = OFlags::PATH | OFlags::NOFOLLOW | OFlags::CLOEXEC;
    let old = open(path, flags, Mode::empty()).ok()?;
    let is_file =
        fstat(&old).is_ok_and(|s| FileType::from_raw_mode(s.st_mode) == FileType::RegularFile);
    let swapped =
        is_file && renameat_with(CWD, tmp.path(), CWD, path, RenameFlags::EXCHANGE).is_ok();
    swapped.then(|| std::fs::File::from(old))
}

/// Elsewhere a rename replaces the file.
#[cfg(not(target_os = "linux"))]
fn exchanged(_: &tempfile::NamedTempFile, _: &Path) -> Option<std::fs::File> {
    None
}

/// Writes `model` to `output`: a `.obj` (any case) with its `.mtl` and textures in the same
/// folder (those first, the `.obj` last), anything else as `.glb` with `meta`.
pub fn write_model(
    model: &Model,
    meta: &ExportMeta,
    output: &Path,
    instancing: Instancing,
) -> anyhow::Result<()> {
    write_model_into(model, meta, output, instancing, None)
}

/// [`write_model`], a `.glb` into the pages `reserved` for it when given (and when they can
/// be linked into the folder; a new temporary file otherwise). The same bytes either way.
pub fn write_model_into(
    model: &Model,
    meta: &ExportMeta,
    output: &Path,
    instancing: Instancing,
    reserved: Option<Reserved>,
) -> anyhow::Result<()> {
    let is_obj = output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if is_obj {
        let stem = output
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let mtl = format!("{stem}.mtl");
        let files = obj_files(model, &mtl, &stem)?;
        let dir = output.parent().map(Path::to_path_buf).unwrap_or_default();
        for (name, png) in &files.textures {
            write_atomically(&dir.join(name), png)?;
        }
        write_atomically(&dir.join(&mtl), files.mtl.as_bytes())?;
        write_atomically(output, files.obj.as_bytes())?;
    } else {
        // Streamed from the model's memory: no buffer of the file's size. This thread builds
        // the glb and writes it; the temporary file is created (a tenth of a millisecond on
        // ext4) and the model checked on the pool meanwhile; the file takes its place once
        // the check passed.
        let file = write_glb_with(
            model,
            meta,
            instancing,
            || {
                let reserved = reserved.and_then(|r| {
                    let len = r.len;
                    AtomicFile::from_reserved(output, r).ok().map(|f| (f, len))
                });
                match reserved {
                    Some((file, len)) => Ok((file, Some(len))),
                    None => AtomicFile::create(output).map(|file| (file, None)),
                }
            },
            |(mut file, reserved), glb| {
                glb.write_to(file.tmp.as_file_mut())
                    .with_context(|| format!("cannot write {}", output.display()))?;
                // A reserved file is as long as the old one: cut to the new one's length.
                if reserved.is_some_and(|len| len != glb.len()) {
                    file.tmp
                        .as_file()
                        .set_len(glb.len())
                        .with_context(|| format!("cannot write {}", output.display()))?;
                }
                Ok(file)
            },
        )?;
        file.finish()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_nothing_and_names_the_folder() {
        let dir = tempfile::tempdir().expect("tempdir");
        let missing = dir.path().join("missing").join("tree.glb");
        let err = write_atomically(&missing, b"glTF").expect_err("no such folder");
        assert!(format!("{err:#}").contains("missing"), "{err:#}");
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
    }

    #[test]
    fn an_existing_file_is_replaced_whole() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.glb");
        std::fs::write(&path, b"an older and longer content").expect("write");
        write_atomically(&path, b"new").expect("replaced");
        assert_eq!(std::fs::read(&path).expect("read"), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
        // Again over the new file, and a failed write leaves it as it was.
        write_atomically(&path, b"newer").expect("replaced");
        let failed = write_atomically_with(&path, |file| {
            file.write_all(b"half")?;
            Err(std::io::Error::other("the disk is full"))
        });
        assert!(format!("{:#}", failed.expect_err("fails")).contains("disk is full"));
        assert_eq!(std::fs::read(&path).expect("read"), b"newer");
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
    }

    #[test]
    fn a_folder_in_the_way_is_neither_replaced_nor_moved() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.glb");
        std::fs::create_dir(&path).expect("mkdir");
        write_atomically(&path, b"glTF").expect_err("a folder is in the way");
        assert!(path.is_dir());
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
    }

    /// A model of `n` triangles in a row.
    fn strip(n: u32) -> Model {
        use pge_engine::geometry::Mesh;
        let positions = (0..n + 2)
            .map(|k| glam::Vec3::new(k as f32, (k % 2) as f32, 0.0))
            .collect();
        let indices = (0..n).flat_map(|k| [k, k + 1, k + 2]).collect();
        let mut model = Model::new();
        let mesh = Mesh::from_triangles(positions, indices).expect("mesh");
        model.add_mesh(mesh, glam::Mat4::IDENTITY);
        model
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_glb_written_into_reserved_pages_is_the_same_file_and_leaves_nothing_behind() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("tempdir");
        let meta = ExportMeta::default();
        let want = |model: &Model| {
            let path = dir.path().join("want.glb");
            write_model(model, &meta, &path, Instancing::Gpu).expect("written");
            let bytes = std::fs::read(&path).expect("read");
            std::fs::remove_file(&path).expect("removed");
            bytes
        };
        let path = dir.path().join("tree.glb");
        // Nothing to reserve for a file that is not there.
        assert!(reserve(&path, false).is_none());
        // A longer old file (the new one is cut to its length), then a shorter one.
        for (old, triangles) in [(100_000, 10), (10, 1_000)] {
            std::fs::write(&path, vec![7u8; old]).expect("old file");
            let reserved = reserve(&path, false).expect("reserved on any file system");
            assert_eq!(reserved.len, old as u64);
            // No name in the folder until it is written.
            assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
            let model = strip(triangles);
            write_model_into(&model, &meta, &path, Instancing::Gpu, Some(reserved))
                .expect("written");
            assert!(std::fs::read(&path).expect("read") == want(&model));
            assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
            let reference = dir.path().join("reference");
            std::fs::File::create(&reference).expect("create");
            let mode = |p: &Path| std::fs::metadata(p).expect("meta").permissions().mode() & 0o777;
            assert_eq!(mode(&path), mode(&reference));
            std::fs::remove_file(&reference).expect("removed");
        }
        // Pages reserved and never used leave nothing either.
        drop(reserve(&path, false).expect("reserved"));
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn written_files_honour_the_umask_like_any_new_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("tempdir");
        let reference = dir.path().join("reference");
        std::fs::File::create(&reference).expect("create");
        let path = dir.path().join("model.glb");
        write_atomically(&path, b"glTF").expect("written");
        let mode = |p: &Path| std::fs::metadata(p).expect("metadata").permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&reference));
    }
}
