//! The generation worker: a background thread that owns the Lua sessions.
//!
//! Lua states cannot move between threads, so each generation creates its session on this
//! thread. Requests that queued up while a generation ran are superseded by the newest one.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use std::time::Instant;

use pge_engine::{Engine, SessionOptions};

use super::reload::{Generation, Outcome, Report, Request};
use super::scene::Scene;
use super::watch::watch_key;

/// The worker thread and the channel to it. Dropping it stops the thread after the running
/// generation (which the owner should cancel first).
pub struct Worker {
    requests: Option<Sender<Request>>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the thread. Every report goes to `reports`, then `wake` is called (to repaint
    /// the window).
    pub fn start(
        engine: Arc<Engine>,
        reports: Sender<Report>,
        wake: impl Fn() + Send + 'static,
    ) -> std::io::Result<Worker> {
        let (tx, rx) = channel::<Request>();
        let thread = std::thread::Builder::new()
            .name("pge-generate".into())
            .spawn(move || serve(&engine, &rx, &reports, &wake))?;
        Ok(Worker {
            requests: Some(tx),
            thread: Some(thread),
        })
    }

    /// Queues a request.
    pub fn send(&self, request: Request) {
        if let Some(tx) = &self.requests {
            // The thread only ends when this sender is dropped, so sending cannot fail.
            let _ = tx.send(request);
        }
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.requests = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn serve(engine: &Engine, rx: &Receiver<Request>, reports: &Sender<Report>, wake: &dyn Fn()) {
    while let Ok(mut request) = rx.recv() {
        // Only the newest queued request matters.
        while let Ok(newer) = rx.try_recv() {
            let old = std::mem::replace(&mut request, newer);
            let _ = reports.send(Report {
                id: old.id,
                outcome: Outcome::Cancelled,
            });
        }
        let outcome = generate(engine, &request);
        if reports
            .send(Report {
                id: request.id,
                outcome,
            })
            .is_err()
        {
            return;
        }
        wake();
    }
}

/// Runs one generation: the script, then its algorithm to the end or to the requested step
/// count, then prepares the model for drawing.
pub fn generate(engine: &Engine, request: &Request) -> Outcome {
    if !request.script.is_file() {
        return Outcome::Gone;
    }
    let settings = &request.settings;
    let options = SessionOptions {
        seed: settings.seed,
        params: settings.params.clone(),
        steps: settings.steps,
        cancel: Some(request.cancel.clone()),
    };
    let session = match engine.session(options) {
        Ok(s) => s,
        Err(e) => {
            return Outcome::Failed {
                message: e.to_string(),
                loaded: Vec::new(),
            };
        }
    };
    let t0 = Instant::now();
    let mut taken = 0u32;
    let result = (|| {
        let value = session.run_script(&request.script)?;
        let script_seconds = t0.elapsed().as_secs_f64();
        let mut algorithm = session.algorithm_from(value)?;
        let ctx = session.context();
        let mut model = pge_engine::algorithm::run(&mut *algorithm, &ctx, &mut |s| taken = s)?;
        model
            .stats
            .phases
            .insert(0, ("script".into(), script_seconds));
        model.validate()?;
        Ok::<_, pge_engine::Error>(model)
    })();
    let loaded = loaded_files(&request.script, session.loaded_files());
    if request.cancel.load(Ordering::Relaxed) {
        return Outcome::Cancelled;
    }
    match result {
        Ok(mut model) => {
            let t1 = Instant::now();
            let scene = Scene::new(&model);
            model.stats.add_phase("preview", t1.elapsed().as_secs_f64());
            let params = session.declared_params();
            Outcome::Generated(Box::new(Generation {
                scene: Arc::new(scene),
                model: Arc::new(model),
                params,
                loaded,
                steps_taken: taken,
                finished: settings.steps.is_none_or(|n| taken < n),
                seconds: t0.elapsed().as_secs_f64(),
                settings: settings.clone(),
            }))
        }
        Err(e) => Outcome::Failed {
            message: one_line(&e.to_string()),
            loaded,
        },
    }
}

/// The files to watch after a run: the script and what the session read, as watch keys.
fn loaded_files(script: &Path, loaded: Vec<PathBuf>) -> Vec<PathBuf> {
    let mut out = vec![watch_key(script)];
    for path in loaded {
        let key = watch_key(&path);
        if !out.contains(&key) {
            out.push(key);
        }
    }
    out
}

/// The first line of an error (the traceback stays in the terminal).
fn one_line(message: &str) -> String {
    message.lines().next().unwrap_or_default().to_string()
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;
    use std::time::Duration;

    use super::super::reload::Settings;
    use super::*;

    fn request(id: u64, script: &Path, settings: Settings) -> Request {
        Request {
            id,
            script: script.to_path_buf(),
            settings,
            cancel: Arc::new(AtomicBool::new(false)),
        }
    }

    const TRIANGLE: &str = r#"
        local p = pge.params{ size = {1, min = 0.5, max = 4, doc = "edge"} }
        return pge.mesh{ positions = {0,0,0, p.size,0,0, 0,p.size,0}, indices = {0,1,2} }
    "#;

    #[test]
    fn generates_a_model_with_params_and_loaded_files() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("tri.lua");
        std::fs::write(&script, TRIANGLE).expect("write");
        let engine = Engine::builder().build().expect("engine");
        let settings = Settings {
            params: vec![("size".into(), "2".into())],
            ..Settings::default()
        };
        let Outcome::Generated(g) = generate(&engine, &request(1, &script, settings)) else {
            panic!("expected a model")
        };
        assert_eq!(g.model.triangle_count(), 1);
        assert_eq!(g.scene.bounds.map(|b| b.1.x), Some(2.0));
        assert_eq!(g.params.len(), 1);
        assert_eq!(g.params[0].name, "size");
        assert_eq!(g.params[0].max, Some(4.0));
        assert!(g.loaded.contains(&watch_key(&script)));
        assert!(g.finished);
    }

    #[test]
    fn the_step_scrubber_stops_step_wise_algorithms_early() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("grow.lua");
        std::fs::write(
            &script,
            r#"
            local n = 0
            local tri = pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }
            return pge.Algorithm{
                init = function() n = 0 end,
                step = function() n = n + 1; return n < 5 end,
                finish = function()
                    local m = pge.model()
                    for i = 1, n do m:add(tri) end
                    return m
                end,
            }
            "#,
        )
        .expect("write");
        let engine = Engine::builder().build().expect("engine");
        let Outcome::Generated(full) = generate(&engine, &request(1, &script, Settings::default()))
        else {
            panic!("expected a model")
        };
        assert_eq!((full.steps_taken, full.finished), (5, true));
        assert_eq!(full.model.triangle_count(), 5);
        let two = Settings {
            steps: Some(2),
            ..Settings::default()
        };
        let Outcome::Generated(part) = generate(&engine, &request(2, &script, two)) else {
            panic!("expected a model")
        };
        assert_eq!((part.steps_taken, part.finished), (2, false));
        assert_eq!(part.model.triangle_count(), 2);
    }

    #[test]
    fn script_errors_missing_scripts_and_cancellation() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("bad.lua");
        std::fs::write(&script, "local x = 1\nreturn pge.mesh{ positions = 3 }\n").expect("write");
        let engine = Engine::builder().build().expect("engine");
        match generate(&engine, &request(1, &script, Settings::default())) {
            Outcome::Failed { message, .. } => {
                assert!(message.contains("bad.lua:2:"), "{message}");
                assert!(!message.contains('\n'));
            }
            other => panic!("expected an error, got {other:?}"),
        }
        let gone = dir.path().join("gone.lua");
        assert!(matches!(
            generate(&engine, &request(2, &gone, Settings::default())),
            Outcome::Gone
        ));
        std::fs::write(&script, "while true do end").expect("write");
        let req = request(3, &script, Settings::default());
        let cancel = req.cancel.clone();
        let stopper = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            cancel.store(true, Ordering::Relaxed);
        });
        assert!(matches!(generate(&engine, &req), Outcome::Cancelled));
        stopper.join().expect("joined");
    }

    #[test]
    fn the_thread_reports_and_supersedes_queued_requests() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("tri.lua");
        std::fs::write(&script, TRIANGLE).expect("write");
        let engine = Arc::new(Engine::builder().build().expect("engine"));
        let (tx, rx) = channel();
        let worker = Worker::start(engine, tx, || {}).expect("thread");
        for id in 1..=3 {
            worker.send(request(
                id,
                &script,
                Settings {
                    seed: id,
                    ..Settings::default()
                },
            ));
        }
        let mut last = None;
        while last.is_none() {
            let report = rx.recv_timeout(Duration::from_secs(30)).expect("a report");
            if report.id == 3 {
                last = Some(report);
            }
        }
        let Some(Report {
            outcome: Outcome::Generated(g),
            ..
        }) = last
        else {
            panic!("model")
        };
        assert_eq!(g.settings.seed, 3);
        drop(worker);
    }
}
