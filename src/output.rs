//! Writing a model to disk, shared by `pge run` and the preview's export: `.glb`, or `.obj`
//! with its `.mtl` and textures next to it, every file written atomically.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
pub use pge::embed::export_meta;
use pge_engine::export::{
    ExportLimit, ExportMeta, Instancing, Prepared, UsdFiles, obj_files_checked, usd_files,
    usdz_bytes, write_glb_checked,
};
use pge_engine::geometry::Model;

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

/// Writes every file of a set (`path`, bytes) to a temporary file first, and puts them in
/// place only once all are written: a failure on the way leaves every path as it was (an
/// `.obj` with its `.mtl` and textures, shared variants' binary file and description).
pub fn write_set(files: &[(PathBuf, &[u8])]) -> anyhow::Result<()> {
    let mut written = Vec::with_capacity(files.len());
    for (path, bytes) in files {
        let mut file = AtomicFile::create(path)?;
        file.tmp
            .as_file_mut()
            .write_all(bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
        written.push(file);
    }
    // What would make a rename fail half-way through the set: a folder in a file's place.
    if let Some((path, _)) = files.iter().find(|(p, _)| p.is_dir()) {
        anyhow::bail!("cannot write {}: a folder is in the way", path.display());
    }
    for file in written {
        file.finish()?;
    }
    Ok(())
}

/// The prefix of the temporary files `pge` writes beside its outputs, followed by the
/// writing process's id and a dash: `.pge-tmp-PID-XXXXXX`.
const TMP_PREFIX: &str = ".pge-tmp-";

/// A file being written at `path` as [`write_atomically_with`] does: its temporary file,
/// created before the bytes are ready (a `.glb` is built meanwhile).
struct AtomicFile<'a> {
    tmp: tempfile::NamedTempFile,
    path: &'a Path,
    /// Keeps the temporary file on the list a signal clears.
    _in_flight: InFlight,
}

impl<'a> AtomicFile<'a> {
    /// The temporary file for `path`, in the same folder (where temporary files a killed
    /// run of `pge` left are removed first).
    fn create(path: &'a Path) -> anyhow::Result<AtomicFile<'a>> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        remove_stale(&dir);
        let prefix = format!("{TMP_PREFIX}{}-", std::process::id());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            // The kernel applies the umask to the mode given at creation.
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder
            .tempfile_in(&dir)
            .with_context(|| format!("cannot write in {}", dir.display()))?;
        let in_flight = InFlight::new(tmp.path());
        Ok(AtomicFile {
            tmp,
            path,
            _in_flight: in_flight,
        })
    }

    /// Puts the written temporary file in `path`'s place.
    fn finish(self) -> anyhow::Result<()> {
        let AtomicFile { tmp, path, .. } = self;
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

/// The temporary files being written now, removed by [`remove_on_signals`]'s thread.
static IN_FLIGHT: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A temporary file's place on the [`IN_FLIGHT`] list, for as long as it is held.
struct InFlight(PathBuf);

impl InFlight {
    fn new(path: &Path) -> InFlight {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        if let Ok(mut list) = IN_FLIGHT.lock() {
            list.push(path.clone());
        }
        InFlight(path)
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        if let Ok(mut list) = IN_FLIGHT.lock()
            && let Some(k) = list.iter().position(|p| *p == self.0)
        {
            list.swap_remove(k);
        }
    }
}

/// On SIGINT or SIGTERM, removes the temporary files being written and ends the process as
/// the signal would (exit status 128 + its number): an interrupted run leaves nothing
/// half-written and no temporary file behind.
#[cfg(unix)]
pub fn remove_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    let _ = std::thread::Builder::new()
        .name("pge-signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                // The list stays locked: no new temporary file is registered meanwhile.
                let list = IN_FLIGHT
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                for path in list.iter() {
                    let _ = std::fs::remove_file(path);
                }
                std::process::exit(128 + signal);
            }
        });
}

/// Elsewhere the default handling stays.
#[cfg(not(unix))]
pub fn remove_on_signals() {}

/// Removes the temporary files in `dir` that a `pge` process no longer running left there
/// (killed while it wrote: `.pge-tmp-PID-...` whose process is gone). Files of running
/// processes, and every other file, are left alone. Only where a process can be looked up
/// (Linux's `/proc`).
fn remove_stale(dir: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(TMP_PREFIX))
            .and_then(|rest| rest.split_once('-'))
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let gone = !Path::new("/proc").join(pid.to_string()).exists();
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        if gone && regular {
            let _ = std::fs::remove_file(entry.path());
        }
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
/// folder (all written before any takes its place, the `.obj` last), a `.usda` or `.usdz` as
/// [`write_usd`] does, anything else as `.glb` with `meta` (the skeletons' texts taken from
/// `prepared` where it has them). The export keeps to `limit` (the run's deadline): checked
/// before it, inside the glb's build and the `.obj` writer's loop, and before the files are
/// written; its error stops the export with nothing written.
pub fn write_model(
    model: &Model,
    prepared: &Prepared,
    meta: &ExportMeta,
    output: &Path,
    instancing: Instancing,
    limit: &ExportLimit,
) -> anyhow::Result<()> {
    limit.check()?;
    let is_obj = output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if usd_kind(output).is_some() {
        let files = usd_files(model, meta, &usd_folder(output))?;
        limit.check()?;
        write_usd(&files, output)?;
    } else if is_obj {
        let stem = output
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let mtl = format!("{stem}.mtl");
        // The text is held whole until it is written: it must fit the run's memory budget.
        let files = obj_files_checked(model, &mtl, &stem, &mut |bytes| {
            limit.check()?;
            limit.ctx.budget.check(bytes as u64, &limit.at, || {
                format!(
                    "the .obj text (past {} MiB, every placement written out)",
                    bytes.div_ceil(1 << 20)
                )
            })
        })?;
        limit.check()?;
        let dir = output.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut set: Vec<(PathBuf, &[u8])> = files
            .textures
            .iter()
            .map(|(name, png)| (dir.join(name), png.as_slice()))
            .collect();
        set.push((dir.join(&mtl), files.mtl.as_bytes()));
        set.push((output.to_path_buf(), files.obj.as_bytes()));
        write_set(&set)?;
    } else {
        // Streamed from the model's memory: no buffer of the file's size. This thread builds
        // the glb and writes it; the temporary file is created (a tenth of a millisecond on
        // ext4) and the model checked on the pool meanwhile; the file takes its place once
        // the check passed.
        let file = write_glb_checked(
            model,
            prepared,
            meta,
            instancing,
            limit,
            || AtomicFile::create(output),
            |mut file, glb| {
                glb.write_to(file.tmp.as_file_mut())
                    .with_context(|| format!("cannot write {}", output.display()))?;
                Ok(file)
            },
        )?;
        file.finish()?;
    }
    Ok(())
}

/// `usda` or `usdz` when `path` ends so (any case).
#[must_use]
pub fn usd_kind(path: &Path) -> Option<&'static str> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    ["usda", "usdz"].into_iter().find(|k| *k == ext)
}

/// The folder of a USD layer's textures: its file name without the extension.
#[must_use]
pub fn usd_folder(output: &Path) -> String {
    output
        .file_stem()
        .unwrap_or_default()
        .to_string_lossy()
        .to_string()
}

/// Writes a USD export to `output`: a `.usdz` package with the textures inside, or a
/// `.usda` with its textures in the folder beside it, the whole set put in place together
/// ([`write_set`]).
pub fn write_usd(files: &UsdFiles, output: &Path) -> anyhow::Result<()> {
    if usd_kind(output) == Some("usdz") {
        let name = Path::new(&usd_folder(output)).with_extension("usda");
        let bytes = usdz_bytes(&name.to_string_lossy(), files)?;
        return write_atomically(output, &bytes);
    }
    let dir = output.parent().map(Path::to_path_buf).unwrap_or_default();
    if !files.textures.is_empty() {
        let folder = dir.join(usd_folder(output));
        std::fs::create_dir_all(&folder)
            .with_context(|| format!("cannot create {}", folder.display()))?;
    }
    let mut set: Vec<(PathBuf, &[u8])> = files
        .textures
        .iter()
        .map(|(path, texture)| (dir.join(path), texture.encoded.as_slice()))
        .collect();
    set.push((output.to_path_buf(), files.layer.as_bytes()));
    write_set(&set)
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
