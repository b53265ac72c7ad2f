//! The glb built and written by the calling thread while the rayon pool opens the file it
//! goes to and checks the model.

use std::sync::PoisonError;

use super::{Builder, ExportMeta, GlbFile, Instancing, Prepared};
use crate::Error;
use crate::export::ExportLimit;
use crate::geometry::Model;

/// [`glb_file_with`](super::glb_file_with) (the skeletons' texts taken from `prepared` where
/// it has them), handed to `write` as soon as it is built, with
/// what `open` made beside the build (the temporary file it goes to), while the model is
/// checked (a pass over every number and index) on the rayon pool. Building reads no index or
/// number in a way that could fail on an invalid model, and the check's error comes first
/// (then the build's, `open`'s and `write`'s), as if it had run before: what `open` and
/// `write` made is then dropped, so `write` must write where that takes it back (a temporary
/// file).
///
/// The calling thread builds and writes: only `open` and the check go to the pool, as one
/// job, and the calling thread opens the file itself when that job has not started by the
/// time the glb is built (with one thread, everything runs on the calling thread, the check
/// first), so a caller outside the pool (`pge run`'s main thread) neither hands the work
/// over nor waits to be woken after it.
pub fn write_glb_with<F, T, E>(
    model: &Model,
    prepared: &Prepared,
    meta: &ExportMeta,
    instancing: Instancing,
    open: impl FnOnce() -> std::result::Result<F, E> + Send,
    write: impl FnOnce(F, GlbFile) -> std::result::Result<T, E>,
) -> std::result::Result<T, E>
where
    F: Send,
    E: From<Error> + Send,
{
    let limit = ExportLimit::default();
    write_glb_checked(model, prepared, meta, instancing, &limit, open, write)
}

/// [`write_glb_with`] within a run's deadline: the build checks `limit` per mesh, per group
/// and every 65536 placements, and once more before `write` is handed the file; its error
/// stops the export before anything is written.
pub fn write_glb_checked<F, T, E>(
    model: &Model,
    prepared: &Prepared,
    meta: &ExportMeta,
    instancing: Instancing,
    limit: &ExportLimit,
    open: impl FnOnce() -> std::result::Result<F, E> + Send,
    write: impl FnOnce(F, GlbFile) -> std::result::Result<T, E>,
) -> std::result::Result<T, E>
where
    F: Send,
    E: From<Error> + Send,
{
    let write = |opened: F, file: GlbFile| {
        limit.check()?;
        write(opened, file)
    };
    let build = || {
        let mut b = Builder::new();
        b.limit = limit.clone();
        b.instancing = instancing;
        b.root.scene = Some(b.scene(model, "pge")?);
        b.file(model, prepared, meta, None)
    };
    if rayon::current_num_threads() == 1 {
        model.validate().map_err(Error::from)?;
        let file = build()?;
        return write(open()?, file);
    }
    let mut valid = Ok(());
    // `open` is taken by whichever comes first: the pool's thread, or the calling thread
    // once the glb is built (when the pool's thread has not woken yet, 30-100 µs on a VM).
    let open = std::sync::Mutex::new(Some(open));
    let take_open = || open.lock().unwrap_or_else(PoisonError::into_inner).take();
    let written = rayon::in_place_scope(|s| {
        // One job, so one thread of the pool is woken (on two cores, a second would take
        // the calling thread's core): it opens the file unless it was taken, hands it back
        // through a channel of one, then checks the model. Should the build fail, the file
        // made is dropped with the channel.
        let (opened_tx, opened) = std::sync::mpsc::sync_channel(1);
        let valid = &mut valid;
        s.spawn(move |_| {
            if let Some(open) = take_open() {
                let _ = opened_tx.send(open());
            }
            *valid = model.validate();
        });
        let file = build()?;
        let opened = match take_open() {
            Some(open) => open(),
            None => match opened.recv() {
                Ok(opened) => opened,
                // `open` panicked: the scope resumes its panic as it ends.
                Err(_) => Err(Error::Export("the output could not be opened".into()).into()),
            },
        };
        write(opened?, file)
    });
    valid.map_err(Error::from)?;
    written
}
