//! The live model: the reloader wired to the generation worker and the file watcher, without
//! any window (the window calls [`Live::pump`] every frame; tests call it in a loop).

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;

use pge_engine::Engine;

use super::reload::{DEBOUNCE, Reloader, Report, Settings};
use super::watch::{Watcher, watch_key};
use super::worker::Worker;

/// The reloader, the worker thread and the watcher, connected.
pub struct Live {
    reloader: Reloader,
    worker: Worker,
    reports: Receiver<Report>,
    watcher: Option<Watcher>,
    file_events: Receiver<Vec<PathBuf>>,
    watched: BTreeSet<PathBuf>,
    watch_error: Option<String>,
}

impl Live {
    /// Starts the worker and the watcher for `script`. `wake` is called from other threads
    /// when a report or a file event arrives (the window repaints then).
    pub fn start(
        engine: Arc<Engine>,
        script: PathBuf,
        settings: Settings,
        wake: impl Fn() + Clone + Send + 'static,
    ) -> std::io::Result<Live> {
        let (report_tx, reports) = channel();
        let worker = Worker::start(engine, report_tx, wake.clone())?;
        let (event_tx, file_events) = channel();
        let (watcher, watch_error) = match Watcher::new(event_tx, wake) {
            Ok(w) => (Some(w), None),
            Err(e) => (None, Some(format!("live reload is off: {e}"))),
        };
        let key = watch_key(&script);
        Ok(Live {
            reloader: Reloader::new(script, key, settings, DEBOUNCE),
            worker,
            reports,
            watcher,
            file_events,
            watched: BTreeSet::new(),
            watch_error,
        })
    }

    /// Takes file events and worker reports, starts the generation due, updates the watched
    /// folders. Returns whether the model changed.
    pub fn pump(&mut self, now: Instant) -> bool {
        while let Ok(paths) = self.file_events.try_recv() {
            self.reloader.file_event(&paths, now);
        }
        let mut changed = false;
        while let Ok(report) = self.reports.try_recv() {
            changed |= self.reloader.report(report, now);
        }
        if let Some(request) = self.reloader.poll(now) {
            self.worker.send(request);
        }
        if self.watched != *self.reloader.watched() {
            self.watched = self.reloader.watched().clone();
            if let Some(w) = &mut self.watcher {
                self.watch_error = w
                    .watch_files(&self.watched)
                    .err()
                    .map(|e| format!("watching: {e}"));
            }
        }
        changed
    }

    /// The reload state.
    #[must_use]
    pub fn reloader(&self) -> &Reloader {
        &self.reloader
    }

    /// The reload state, to change settings.
    pub fn reloader_mut(&mut self) -> &mut Reloader {
        &mut self.reloader
    }

    /// Why live reload does not work, if it does not.
    #[must_use]
    pub fn watch_error(&self) -> Option<&str> {
        self.watch_error.as_deref()
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        self.reloader.cancel_running();
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::time::Duration;

    use super::super::reload::Status;
    use super::*;

    /// Pumps until `done` holds (or 30 s pass).
    fn pump_until(live: &mut Live, what: &str, done: impl Fn(&Reloader) -> bool) {
        let end = Instant::now() + Duration::from_secs(30);
        while Instant::now() < end {
            live.pump(Instant::now());
            if done(live.reloader()) {
                return;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        panic!(
            "timed out waiting for {what}: status {:?}",
            live.reloader().status()
        );
    }

    fn triangles_of(r: &Reloader) -> Option<u64> {
        r.current().map(|g| g.model.triangle_count() as u64)
    }

    fn triangles(n: usize) -> String {
        format!(
            "local m = pge.model()\nlocal t = require('part')\nfor i = 1, {n} do m:add(t) end\nreturn m\n"
        )
    }

    fn write(path: &Path, text: &str) {
        std::fs::write(path, text).expect("write");
    }

    #[test]
    fn saves_reload_errors_keep_the_model_and_deletion_waits() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("main.lua");
        let part = dir.path().join("part.lua");
        write(
            &part,
            "return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n",
        );
        write(&script, &triangles(2));
        let engine = Arc::new(Engine::builder().build().expect("engine"));
        let mut live =
            Live::start(engine, script.clone(), Settings::default(), || {}).expect("start");
        pump_until(&mut live, "the first model", |r| triangles_of(r) == Some(2));
        assert!(
            live.reloader().watched().contains(&watch_key(&part)),
            "modules are watched"
        );

        write(&script, &triangles(3));
        pump_until(&mut live, "the saved model", |r| triangles_of(r) == Some(3));

        // A broken module: the error names it, the last good model stays.
        write(
            &part,
            "local a = 1\nreturn pge.mesh{ positions = {0,0,0}, indices = {0,1,2} }\n",
        );
        pump_until(&mut live, "the module's error", |r| {
            matches!(r.status(), Status::Error(_))
        });
        let Status::Error(message) = live.reloader().status().clone() else {
            unreachable!()
        };
        assert!(message.contains("part.lua:2:"), "{message}");
        assert_eq!(triangles_of(live.reloader()), Some(3));

        // Fixing the module brings a model back.
        write(
            &part,
            "return pge.mesh{ positions = {0,0,0, 2,0,0, 0,2,0}, indices = {0,1,2} }\n",
        );
        pump_until(&mut live, "the fixed model", |r| {
            r.status() == &Status::Ready
                && r.current().and_then(|g| g.scene.bounds).map(|b| b.1.x) == Some(2.0)
        });

        // Deleted: gone, model kept; back: regenerated.
        std::fs::remove_file(&script).expect("remove");
        pump_until(&mut live, "gone", |r| r.status() == &Status::Gone);
        assert_eq!(triangles_of(live.reloader()), Some(3));
        write(&script, &triangles(4));
        pump_until(&mut live, "the script back", |r| triangles_of(r) == Some(4));
    }

    #[test]
    fn a_save_supersedes_a_run_that_never_ends() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("main.lua");
        write(&script, "while true do end\n");
        let engine = Arc::new(Engine::builder().build().expect("engine"));
        let mut live =
            Live::start(engine, script.clone(), Settings::default(), || {}).expect("start");
        pump_until(&mut live, "the endless run to start", Reloader::is_running);
        std::thread::sleep(Duration::from_millis(200));
        write(
            &script,
            "return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n",
        );
        pump_until(&mut live, "the saved model", |r| triangles_of(r) == Some(1));
    }

    /// A plugin whose `pge.crash()` panics: a bug on the generator thread, which no script
    /// can cause in PGE's own plugins.
    struct Crash;

    impl pge_engine::Plugin for Crash {
        fn register(
            &self,
            lua: &pge_engine::mlua::Lua,
            pge: &pge_engine::mlua::Table,
        ) -> pge_engine::mlua::Result<()> {
            pge.set(
                "crash",
                lua.create_function(|_, ()| -> pge_engine::mlua::Result<()> {
                    panic!("a bug in a plugin")
                })?,
            )
        }
    }

    #[test]
    fn a_panic_on_the_generator_thread_is_the_run_s_error_and_the_next_save_runs() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("main.lua");
        write(&script, "local x = 1\npge.crash()\nreturn x\n");
        let engine = Arc::new(Engine::builder().plugin(Crash).build().expect("engine"));
        let mut live =
            Live::start(engine, script.clone(), Settings::default(), || {}).expect("start");
        // The window is told (it does not wait for ever): the panic is the run's error.
        pump_until(&mut live, "the generator's failure", |r| {
            matches!(r.status(), Status::Error(_))
        });
        let Status::Error(message) = live.reloader().status().clone() else {
            unreachable!()
        };
        assert!(message.contains("a bug in a plugin"), "{message}");
        assert!(message.contains("a bug in PGE"), "{message}");
        // The generator thread lives on: a save regenerates.
        write(
            &script,
            "return pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n",
        );
        pump_until(&mut live, "the saved model", |r| triangles_of(r) == Some(1));
    }

    #[test]
    fn slider_changes_regenerate_with_the_new_value() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("main.lua");
        write(
            &script,
            "local p = pge.params{ n = {1, min = 1, max = 9} }\nlocal m = pge.model()\n\
             local t = pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n\
             for i = 1, p.n do m:add(t) end\nreturn m\n",
        );
        let engine = Arc::new(Engine::builder().build().expect("engine"));
        let mut live = Live::start(engine, script, Settings::default(), || {}).expect("start");
        pump_until(&mut live, "the first model", |r| triangles_of(r) == Some(1));
        let mut s = live.reloader().settings().clone();
        s.set_param("n", "5".into());
        live.reloader_mut().set_settings(s);
        pump_until(&mut live, "the model with n = 5", |r| {
            triangles_of(r) == Some(5)
        });
    }
}
