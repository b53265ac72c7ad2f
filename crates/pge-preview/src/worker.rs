//! The generation worker: a background thread that owns the Lua sessions.
//!
//! Lua states cannot move between threads, so each generation creates its session on this
//! thread. Requests that queued up while a generation ran are superseded by the newest one.
//! The thread keeps copies of the last algorithm's state every few steps ([`Kept`]), so that
//! moving the step scrubber re-runs from the nearest copy instead of the whole script.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use std::time::{Instant, SystemTime};

use pge_engine::geometry::Model;
use pge_engine::{Algorithm, Engine, ParamInfo, RunContext, SessionOptions, Step};

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
    let mut kept = Kept::default();
    while let Ok(mut request) = rx.recv() {
        // Only the newest queued request matters.
        while let Ok(newer) = rx.try_recv() {
            let old = std::mem::replace(&mut request, newer);
            let _ = reports.send(Report {
                id: old.id,
                outcome: Outcome::Cancelled,
            });
        }
        let outcome = guarded(&mut kept, |kept| generate_with(engine, &request, kept));
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

/// `generate` with `kept`, a panic on the way (a bug, never the script's doing) reported
/// as the generation's failure rather than ending the thread the window waits on; what
/// `kept` holds is dropped then.
fn guarded(kept: &mut Kept, generate: impl FnOnce(&mut Kept) -> Outcome) -> Outcome {
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| generate(&mut *kept)));
    run.unwrap_or_else(|panic| {
        kept.clear();
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        Outcome::Failed {
            message: format!("the generator failed (a bug in PGE, please report it): {what}"),
            loaded: Vec::new(),
        }
    })
}

/// Runs one generation: the script, then its algorithm to the end or to the requested step
/// count, then prepares the model for drawing. It resumes from what `kept` holds of the
/// previous generation when only the step count changed (same script and files, seed and
/// parameters), and keeps copies of this one's states for the next.
pub fn generate_with(engine: &Engine, request: &Request, kept: &mut Kept) -> Outcome {
    if !request.script.is_file() {
        kept.clear();
        return Outcome::Gone;
    }
    if let Some(outcome) = kept.resume(request) {
        return outcome;
    }
    let settings = &request.settings;
    let options = SessionOptions {
        seed: settings.seed,
        params: settings.params.clone(),
        steps: settings.steps,
        cancel: Some(request.cancel.clone()),
        ..SessionOptions::default()
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
    let started = SystemTime::now();
    let t0 = Instant::now();
    let mut taken = 0u32;
    let result = (|| {
        kept.scripts_run += 1;
        let value = session.run_script(&request.script)?;
        let script_seconds = t0.elapsed().as_secs_f64();
        let mut algorithm = session.algorithm_from(value)?;
        let ctx = session.context();
        algorithm.init(&ctx)?;
        kept.start(&*algorithm, &ctx);
        taken = kept.advance(&mut *algorithm, &ctx, 0)?;
        let mut model = algorithm.finish(&ctx)?;
        model.remove_unusable_triangles();
        model
            .stats
            .phases
            .insert(0, ("script".into(), script_seconds));
        model.validate()?;
        Ok::<_, pge_engine::Error>(model)
    })();
    let loaded = loaded_files(&request.script, session.loaded_files());
    if request.cancel.load(Ordering::Relaxed) {
        kept.clear();
        return Outcome::Cancelled;
    }
    match result {
        Ok(model) => {
            kept.remember(request, &loaded, session.declared_params(), started);
            generated(request, model, session.declared_params(), loaded, taken, t0)
        }
        Err(e) => {
            kept.clear();
            Outcome::Failed {
                message: one_line(&e.to_string()),
                loaded,
            }
        }
    }
}

/// The outcome of a generation that produced `model` after `taken` steps.
fn generated(
    request: &Request,
    mut model: Model,
    params: Vec<ParamInfo>,
    loaded: Vec<PathBuf>,
    taken: u32,
    t0: Instant,
) -> Outcome {
    let settings = &request.settings;
    let t1 = Instant::now();
    let scene = Scene::new(&model);
    model.stats.add_phase("preview", t1.elapsed().as_secs_f64());
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

/// The most states [`Kept`] holds besides the last; past it every other one is dropped
/// and the spacing doubles. (A copy of a growth costs about 80 bytes per branch: 16 copies
/// of a tree growing to 100 000 branches hold about 70 MB.)
const MAX_KEPT: usize = 16;

/// The first spacing, in steps, of the states [`Kept`] holds.
const FIRST_SPACING: u32 = 4;

/// What the worker keeps of its last generation so that the step scrubber does not re-run
/// the script: copies of the algorithm's state ([`Algorithm::snapshot`]) after init, every
/// few steps (at most [`MAX_KEPT`], the spacing doubling as the run grows longer) and after
/// the last step taken. A request that differs only in its step count restarts from the
/// nearest copy at or before it, so scrubbing back costs at most the spacing in steps and
/// scrubbing forward only the steps added. Algorithms that cannot be copied (their state
/// lives in Lua: `pge.Algorithm`, L-systems with callbacks) re-run the script.
pub struct Kept {
    /// What the copies were grown from; `None` when nothing is kept.
    key: Option<Key>,
    /// States after `n` steps that each returned [`Step::Continue`], by increasing `n`: the
    /// state after init (n = 0), then every `spacing` steps.
    states: Vec<(u32, Box<dyn Algorithm>)>,
    /// Steps between two kept states.
    spacing: u32,
    /// The state after the last step taken, when that step returned [`Step::Continue`].
    head: Option<(u32, Box<dyn Algorithm>)>,
    /// Whether the algorithm can be copied (copies are taken).
    copies: bool,
    /// The steps the algorithm plans to take ([`Algorithm::planned_steps`]).
    planned: Option<u32>,
    /// The run context of the session that ran the script.
    ctx: RunContext,
    /// That session's declared parameters.
    params: Vec<ParamInfo>,
    /// The files it read.
    loaded: Vec<PathBuf>,
    /// Scripts run so far (a resumed generation runs none).
    pub scripts_run: u32,
    /// Algorithm steps taken so far, over every generation.
    pub steps_run: u64,
}

/// What kept states were grown from: a request's script, seed and parameters, and the
/// files the script read as they were then.
struct Key {
    script: PathBuf,
    seed: u64,
    params: Vec<(String, String)>,
    files: Vec<(PathBuf, Option<(u64, SystemTime)>)>,
}

/// A file's length and modification time, `None` if it cannot be read.
fn stamp(path: &Path) -> Option<(u64, SystemTime)> {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.len(), meta.modified().ok()?))
}

impl Default for Kept {
    fn default() -> Self {
        Kept {
            key: None,
            states: Vec::new(),
            spacing: FIRST_SPACING,
            head: None,
            copies: false,
            planned: None,
            ctx: RunContext::default(),
            params: Vec::new(),
            loaded: Vec::new(),
            scripts_run: 0,
            steps_run: 0,
        }
    }
}

impl Kept {
    /// Forgets every kept state.
    pub fn clear(&mut self) {
        self.key = None;
        self.states.clear();
        self.head = None;
        self.copies = false;
        self.spacing = FIRST_SPACING;
    }

    /// Starts keeping the states of a new run, from its state after init.
    fn start(&mut self, algorithm: &dyn Algorithm, ctx: &RunContext) {
        self.clear();
        self.ctx = ctx.clone();
        self.planned = algorithm.planned_steps();
        if let Some(copy) = algorithm.snapshot() {
            self.states.push((0, copy));
            self.copies = true;
        }
    }

    /// Steps `algorithm` from `taken` steps until it is done or has taken `ctx.steps`,
    /// keeping copies on the way; returns the steps taken.
    fn advance(
        &mut self,
        algorithm: &mut dyn Algorithm,
        ctx: &RunContext,
        mut taken: u32,
    ) -> pge_engine::Result<u32> {
        while ctx.steps.is_none_or(|n| taken < n) {
            let step = algorithm.step(ctx)?;
            taken += 1;
            self.steps_run += 1;
            // Done on reaching `ctx.steps` is no end: a larger count goes on from there.
            if step == Step::Done && ctx.steps != Some(taken) {
                return Ok(taken);
            }
            let newer = self.states.last().is_some_and(|&(n, _)| n < taken);
            if self.copies
                && taken.is_multiple_of(self.spacing)
                && newer
                && let Some(copy) = algorithm.snapshot()
            {
                self.states.push((taken, copy));
                if self.states.len() > MAX_KEPT {
                    self.spacing *= 2;
                    let spacing = self.spacing;
                    self.states.retain(|&(n, _)| n.is_multiple_of(spacing));
                }
            }
        }
        if self.copies {
            self.head = algorithm.snapshot().map(|copy| (taken, copy));
        }
        Ok(taken)
    }

    /// After a successful run: remembers what its states were grown from, unless a file it
    /// read changed while it ran (then nothing is kept).
    fn remember(
        &mut self,
        request: &Request,
        loaded: &[PathBuf],
        params: Vec<ParamInfo>,
        started: SystemTime,
    ) {
        let files: Vec<_> = loaded.iter().map(|p| (p.clone(), stamp(p))).collect();
        let changed = files
            .iter()
            .any(|(_, s)| s.is_none_or(|(_, modified)| modified >= started));
        if !self.copies || changed {
            self.clear();
            return;
        }
        self.key = Some(Key {
            script: request.script.clone(),
            seed: request.settings.seed,
            params: request.settings.params.clone(),
            files,
        });
        self.params = params;
        self.loaded = loaded.to_vec();
    }

    /// The generation of `request` from the nearest kept state, if the states fit it (same
    /// script, unchanged files, same seed and parameters).
    fn resume(&mut self, request: &Request) -> Option<Outcome> {
        let key = self.key.as_ref()?;
        let settings = &request.settings;
        let same = key.script == request.script
            && key.seed == settings.seed
            && key.params == settings.params
            && key.files.iter().all(|(p, s)| stamp(p) == *s);
        if !same {
            self.clear();
            return None;
        }
        let t0 = Instant::now();
        let target = settings.steps;
        // To the end: from a state before the planned end, which a step must reach.
        let end = self.planned.unwrap_or(u32::MAX);
        let fits = |n: u32| target.map_or(n < end, |t| n <= t);
        let base = self
            .states
            .iter()
            .chain(&self.head)
            .filter(|(n, _)| fits(*n))
            .max_by_key(|(n, _)| *n);
        let (from, mut algorithm) = base.and_then(|(n, state)| Some((*n, state.snapshot()?)))?;
        let ctx = RunContext {
            steps: target,
            cancel: Some(request.cancel.clone()),
            ..self.ctx.clone()
        };
        let result = (|| {
            let taken = self.advance(&mut *algorithm, &ctx, from)?;
            let mut model = algorithm.finish(&ctx)?;
            model.remove_unusable_triangles();
            model.validate()?;
            Ok::<_, pge_engine::Error>((taken, model))
        })();
        if request.cancel.load(Ordering::Relaxed) {
            return Some(Outcome::Cancelled);
        }
        Some(match result {
            Ok((taken, model)) => generated(
                request,
                model,
                self.params.clone(),
                self.loaded.clone(),
                taken,
                t0,
            ),
            Err(e) => Outcome::Failed {
                message: one_line(&e.to_string()),
                loaded: self.loaded.clone(),
            },
        })
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

    #[test]
    fn a_panic_while_generating_is_the_generation_s_failure() {
        let mut kept = Kept::default();
        let outcome = guarded(&mut kept, |_| panic!("index out of bounds"));
        match outcome {
            Outcome::Failed { message, .. } => {
                assert!(message.contains("index out of bounds"), "{message}");
            }
            other => panic!("expected a failure, got {other:?}"),
        }
        assert!(matches!(
            guarded(&mut kept, |_| Outcome::Gone),
            Outcome::Gone
        ));
    }

    /// A generation with nothing kept from an earlier one.
    fn generate(engine: &Engine, request: &Request) -> Outcome {
        generate_with(engine, request, &mut Kept::default())
    }

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

    /// A scripted `pge.Algorithm` that adds one triangle per step and is done after `steps`
    /// steps, written to `dir/name`.
    fn counting_algorithm(dir: &Path, name: &str, steps: u32) -> PathBuf {
        let script = dir.join(name);
        let text = format!(
            r#"
            local n = 0
            local tri = pge.mesh{{ positions = {{0,0,0, 1,0,0, 0,1,0}}, indices = {{0,1,2}} }}
            return pge.Algorithm{{
                init = function() n = 0 end,
                step = function() n = n + 1; return n < {steps} end,
                finish = function()
                    local m = pge.model()
                    for i = 1, n do m:add(tri) end
                    return m
                end,
            }}
            "#
        );
        std::fs::write(&script, text).expect("write");
        script
    }

    #[test]
    fn the_step_scrubber_stops_step_wise_algorithms_early() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = counting_algorithm(dir.path(), "grow.lua", 5);
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

    /// The model of `script` after `steps`, through `kept`.
    fn scrub(engine: &Engine, script: &Path, steps: Option<u32>, kept: &mut Kept) -> Generation {
        let settings = Settings {
            steps,
            ..Settings::default()
        };
        match generate_with(engine, &request(1, script, settings), kept) {
            Outcome::Generated(g) => *g,
            other => panic!("expected a model, got {other:?}"),
        }
    }

    #[test]
    fn the_scrubber_re_runs_from_the_nearest_kept_state_not_the_script() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("tree.lua");
        std::fs::write(&script, "return pge.Growth{ steps = 40 }\n").expect("write");
        let engine = Engine::builder()
            .plugin(pge_growth::GrowthPlugin)
            .build()
            .expect("engine");
        let mut kept = Kept::default();
        // (steps asked, steps the scrubber takes for it): the first run takes all 40 and
        // keeps a state every 4 steps; then each move starts at the nearest kept state at
        // or before it (20 is kept, 28 for 30, 12 for 13, the last shown, 13, for 15, and
        // 36 for the end, which the 40th step reaches).
        let moves = [
            (Some(40), 40),
            (Some(20), 0),
            (Some(30), 2),
            (Some(13), 1),
            (Some(15), 2),
            (None, 4),
            (Some(8), 0),
        ];
        for (steps, cost) in moves {
            let before = kept.steps_run;
            let g = scrub(&engine, &script, steps, &mut kept);
            assert_eq!(kept.steps_run - before, cost, "to {steps:?}");
            assert_eq!(kept.scripts_run, 1, "to {steps:?}");
            assert_eq!(g.steps_taken, steps.unwrap_or(40));
            assert_eq!(g.finished, steps.is_none());
            // The same model as a run of the whole script to that step.
            let fresh = scrub(&engine, &script, steps, &mut Kept::default());
            assert_eq!(g.model.meshes, fresh.model.meshes, "to {steps:?}");
            assert!(!g.model.meshes.is_empty());
        }
        // Another seed, or a saved script, runs the script again.
        let other_seed = Settings {
            seed: 2,
            steps: Some(20),
            ..Settings::default()
        };
        assert!(matches!(
            generate_with(&engine, &request(2, &script, other_seed), &mut kept),
            Outcome::Generated(_)
        ));
        assert_eq!(kept.scripts_run, 2);
        std::fs::write(&script, "return pge.Growth{ steps = 30, ratio = 0.7 }\n").expect("write");
        let g = scrub(&engine, &script, Some(20), &mut kept);
        assert_eq!(kept.scripts_run, 3);
        let fresh = scrub(&engine, &script, Some(20), &mut Kept::default());
        assert_eq!(g.model.meshes, fresh.model.meshes);
    }

    #[test]
    fn kept_states_thin_out_as_the_run_grows_longer() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = dir.path().join("tree.lua");
        std::fs::write(&script, "return pge.Growth{ steps = 100 }\n").expect("write");
        let engine = Engine::builder()
            .plugin(pge_growth::GrowthPlugin)
            .build()
            .expect("engine");
        let mut kept = Kept::default();
        scrub(&engine, &script, None, &mut kept);
        // Every 4 steps up to 64 makes 17 states: every other one goes, then every 8 steps.
        assert_eq!(kept.spacing, 8);
        let steps: Vec<u32> = kept.states.iter().map(|(n, _)| *n).collect();
        assert_eq!(steps, (0..=12).map(|k| 8 * k).collect::<Vec<_>>());
        assert!(kept.states.len() <= MAX_KEPT);
        let before = kept.steps_run;
        let g = scrub(&engine, &script, Some(50), &mut kept);
        assert_eq!(kept.steps_run - before, 2, "from 48");
        assert_eq!(kept.scripts_run, 1);
        let fresh = scrub(&engine, &script, Some(50), &mut Kept::default());
        assert_eq!(g.model.meshes, fresh.model.meshes);
    }

    #[test]
    fn algorithms_that_cannot_be_copied_re_run_the_script() {
        let dir = tempfile::tempdir().expect("tempdir");
        let script = counting_algorithm(dir.path(), "count.lua", 9);
        let engine = Engine::builder().build().expect("engine");
        let mut kept = Kept::default();
        for (k, steps) in [Some(6), Some(3), None].into_iter().enumerate() {
            let g = scrub(&engine, &script, steps, &mut kept);
            assert_eq!(g.model.triangle_count(), steps.unwrap_or(9) as usize);
            assert_eq!(kept.scripts_run, k as u32 + 1);
        }
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
