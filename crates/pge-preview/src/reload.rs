//! The live-reload state machine, free of windows, threads and clocks.
//!
//! The window feeds it file events, changes of the side panel and the reports of the
//! generation worker, each with the current time; it answers with the generations to start.
//! Rules:
//! - A change of a watched file starts a generation once no further change arrived for the
//!   debounce interval (editors write a file in several steps). That generation supersedes
//!   the one running: the running one is cancelled and its report ignored.
//! - A change in the panel (a slider, the seed, the step scrubber) does not cancel the run in
//!   progress: it is started when that run ends, with the latest settings, so dragging a
//!   slider shows a model for every generation the machine can finish.
//! - The last good model stays until a newer generation succeeds; a failure is shown beside
//!   it, a missing script is reported as gone, and both clear when a later generation
//!   succeeds.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use pge_engine::ParamInfo;
use pge_engine::geometry::Model;

use super::scene::Scene;

/// How long after the last file event a reload starts.
pub const DEBOUNCE: Duration = Duration::from_millis(60);

/// What a generation is run with: the seed, parameter overrides and a step count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Settings {
    /// The run's seed.
    pub seed: u64,
    /// `NAME=VALUE` overrides of declared parameters, as `--set` takes them.
    pub params: Vec<(String, String)>,
    /// Steps to run (`None`: to the end).
    pub steps: Option<u32>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            seed: 1,
            params: Vec::new(),
            steps: None,
        }
    }
}

impl Settings {
    /// Sets the override of `name` (replacing an earlier one).
    pub fn set_param(&mut self, name: &str, value: String) {
        match self.params.iter_mut().find(|(n, _)| n == name) {
            Some((_, v)) => *v = value,
            None => self.params.push((name.to_string(), value)),
        }
    }
}

/// A generation to start on the worker.
#[derive(Clone, Debug)]
pub struct Request {
    /// Increasing number; reports carry it back.
    pub id: u64,
    /// The script to run.
    pub script: PathBuf,
    /// Seed, parameters and steps.
    pub settings: Settings,
    /// Set when a newer request supersedes this one.
    pub cancel: Arc<AtomicBool>,
}

/// A successful generation.
#[derive(Debug)]
pub struct Generation {
    /// The model.
    pub model: Arc<Model>,
    /// The model prepared for drawing (done on the worker thread).
    pub scene: Arc<Scene>,
    /// The main script's declared parameters, with the values used.
    pub params: Vec<ParamInfo>,
    /// Every file the session read (scripts, modules, meshes, textures).
    pub loaded: Vec<PathBuf>,
    /// Steps the algorithm took.
    pub steps_taken: u32,
    /// Whether the algorithm reached its end (not stopped by a step count).
    pub finished: bool,
    /// Wall-clock seconds of the generation, script included.
    pub seconds: f64,
    /// What it was run with.
    pub settings: Settings,
}

/// How a generation ended.
#[derive(Debug)]
pub enum Outcome {
    /// A model.
    Generated(Box<Generation>),
    /// A script error (`FILE:LINE: message`), with the files read before it.
    Failed {
        /// The error, one line.
        message: String,
        /// Files the session read before failing.
        loaded: Vec<PathBuf>,
    },
    /// The script does not exist (deleted, or being replaced by an editor).
    Gone,
    /// Stopped because a newer request superseded it.
    Cancelled,
}

/// A worker's answer to a [`Request`].
#[derive(Debug)]
pub struct Report {
    /// The request's id.
    pub id: u64,
    /// What happened.
    pub outcome: Outcome,
}

/// What the window shows about the state of generation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Status {
    /// A generation is running (and none has finished since the last change).
    Running,
    /// The model on screen is up to date.
    Ready,
    /// The last generation failed with this message.
    Error(String),
    /// The script is missing; waiting for it to come back.
    Gone,
}

/// The state machine. See the module documentation for the rules.
#[derive(Debug)]
pub struct Reloader {
    script: PathBuf,
    key: PathBuf,
    debounce: Duration,
    settings: Settings,
    watched: BTreeSet<PathBuf>,
    /// Time of the last relevant file event not yet acted on.
    changed_at: Option<Instant>,
    /// The panel changed the settings since the running generation started.
    settings_dirty: bool,
    next_id: u64,
    running: Option<(u64, Arc<AtomicBool>, Instant)>,
    current: Option<Generation>,
    status: Status,
    /// Bumped whenever `current` is replaced.
    generation_count: u64,
    /// Seconds from the file event that triggered the last successful generation to its
    /// report (save-to-model latency, without drawing).
    last_latency: Option<Duration>,
    /// The file event that caused the current generation, if one did.
    current_trigger: Option<Instant>,
    trigger_time: Option<(u64, Instant)>,
}

impl Reloader {
    /// A reloader for `script` that will generate with `settings` at the first
    /// [`Reloader::poll`]. `key` is the script's name in file events (see
    /// [`super::watch::watch_key`]); it is watched from the start.
    #[must_use]
    pub fn new(script: PathBuf, key: PathBuf, settings: Settings, debounce: Duration) -> Reloader {
        let watched = BTreeSet::from([key.clone()]);
        Reloader {
            script,
            key,
            debounce,
            settings,
            watched,
            changed_at: None,
            settings_dirty: true,
            next_id: 1,
            running: None,
            current: None,
            status: Status::Running,
            generation_count: 0,
            last_latency: None,
            current_trigger: None,
            trigger_time: None,
        }
    }

    /// The script.
    #[must_use]
    pub fn script(&self) -> &Path {
        &self.script
    }

    /// The files whose change triggers a reload: the script and every file it loaded.
    #[must_use]
    pub fn watched(&self) -> &BTreeSet<PathBuf> {
        &self.watched
    }

    /// The settings of the next generation.
    #[must_use]
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The last good generation, if any.
    #[must_use]
    pub fn current(&self) -> Option<&Generation> {
        self.current.as_ref()
    }

    /// A number that changes whenever [`Reloader::current`] is replaced.
    #[must_use]
    pub fn generation_count(&self) -> u64 {
        self.generation_count
    }

    /// The generation state to show.
    #[must_use]
    pub fn status(&self) -> &Status {
        &self.status
    }

    /// Whether a generation is running.
    #[must_use]
    pub fn is_running(&self) -> bool {
        self.running.is_some()
    }

    /// When the running generation started.
    #[must_use]
    pub fn running_since(&self) -> Option<Instant> {
        self.running.as_ref().map(|r| r.2)
    }

    /// Time from the file event to the report of the last generation a file change caused.
    #[must_use]
    pub fn last_latency(&self) -> Option<Duration> {
        self.last_latency
    }

    /// Cancels the running generation (the window is closing).
    pub fn cancel_running(&self) {
        if let Some((_, cancel, _)) = &self.running {
            cancel.store(true, Ordering::Relaxed);
        }
    }

    /// When the file event that caused the current generation happened (`None` when the
    /// generation came from the panel or the start).
    #[must_use]
    pub fn current_trigger(&self) -> Option<Instant> {
        self.current_trigger
    }

    /// Notes that `paths` changed at `now`; returns whether any of them is watched.
    pub fn file_event<P: AsRef<Path>>(&mut self, paths: &[P], now: Instant) -> bool {
        let relevant = paths.iter().any(|p| self.watched.contains(p.as_ref()));
        if relevant {
            self.changed_at = Some(now);
        }
        relevant
    }

    /// Replaces the settings (from the panel); a generation follows when the running one
    /// ends.
    pub fn set_settings(&mut self, settings: Settings) {
        if settings != self.settings {
            self.settings = settings;
            self.settings_dirty = true;
        }
    }

    /// When [`Reloader::poll`] should be called again at the latest (the end of a debounce).
    #[must_use]
    pub fn next_wake(&self) -> Option<Instant> {
        self.changed_at.map(|t| t + self.debounce)
    }

    /// Decides whether to start a generation now. A file change that has settled cancels the
    /// running generation and supersedes it.
    pub fn poll(&mut self, now: Instant) -> Option<Request> {
        if let Some(t) = self.changed_at {
            if now.duration_since(t) >= self.debounce {
                self.changed_at = None;
                if let Some((_, cancel, _)) = self.running.take() {
                    cancel.store(true, Ordering::Relaxed);
                }
                let request = self.start(now);
                self.trigger_time = Some((request.id, t));
                return Some(request);
            }
            return None;
        }
        if self.settings_dirty && self.running.is_none() {
            return Some(self.start(now));
        }
        None
    }

    fn start(&mut self, now: Instant) -> Request {
        let id = self.next_id;
        self.next_id += 1;
        self.settings_dirty = false;
        let cancel = Arc::new(AtomicBool::new(false));
        self.running = Some((id, cancel.clone(), now));
        if matches!(self.status, Status::Ready) {
            self.status = Status::Running;
        }
        Request {
            id,
            script: self.script.clone(),
            settings: self.settings.clone(),
            cancel,
        }
    }

    /// Takes a worker's report; returns whether the model on screen changed. Reports of
    /// superseded requests are ignored.
    pub fn report(&mut self, report: Report, now: Instant) -> bool {
        if self
            .running
            .as_ref()
            .is_none_or(|(id, _, _)| *id != report.id)
        {
            return false;
        }
        self.running = None;
        match report.outcome {
            Outcome::Generated(generation) => {
                self.watched = BTreeSet::from([self.key.clone()]);
                self.watched.extend(generation.loaded.iter().cloned());
                self.current_trigger = None;
                if let Some((id, t)) = self.trigger_time.take()
                    && id == report.id
                {
                    self.last_latency = Some(now.duration_since(t));
                    self.current_trigger = Some(t);
                }
                self.current = Some(*generation);
                self.generation_count += 1;
                self.status = Status::Ready;
                true
            }
            Outcome::Failed { message, loaded } => {
                // Keep watching what the good version loaded: the fix may be in a module.
                self.watched.extend(loaded);
                self.status = Status::Error(message);
                false
            }
            Outcome::Gone => {
                self.status = Status::Gone;
                false
            }
            Outcome::Cancelled => {
                // Cancelled without being superseded (shutting down): nothing to show.
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn generation(settings: &Settings, loaded: &[&str], nodes: u64) -> Outcome {
        let mut model = Model::new();
        model.stats.nodes = nodes;
        Outcome::Generated(Box::new(Generation {
            scene: Arc::new(Scene::new(&model)),
            model: Arc::new(model),
            params: Vec::new(),
            loaded: loaded.iter().map(PathBuf::from).collect(),
            steps_taken: 3,
            finished: true,
            seconds: 0.1,
            settings: settings.clone(),
        }))
    }

    fn ms(t0: Instant, ms: u64) -> Instant {
        t0 + Duration::from_millis(ms)
    }

    fn reloader() -> Reloader {
        Reloader::new(
            "tree.lua".into(),
            "tree.lua".into(),
            Settings::default(),
            Duration::from_millis(50),
        )
    }

    #[test]
    fn first_poll_starts_a_generation_and_the_model_is_kept() {
        let t0 = Instant::now();
        let mut r = reloader();
        let req = r.poll(t0).expect("starts at once");
        assert_eq!(req.script, PathBuf::from("tree.lua"));
        assert!(r.poll(t0).is_none(), "one run at a time");
        assert_eq!(r.status(), &Status::Running);
        let out = generation(&req.settings, &["tree.lua", "lib/leaf.lua"], 7);
        assert!(r.report(
            Report {
                id: req.id,
                outcome: out
            },
            ms(t0, 10)
        ));
        assert_eq!(r.status(), &Status::Ready);
        assert_eq!(r.current().map(|g| g.model.stats.nodes), Some(7));
        assert!(r.watched().contains(Path::new("lib/leaf.lua")));
        assert!(r.poll(ms(t0, 20)).is_none(), "nothing changed");
    }

    #[test]
    fn file_events_are_debounced_and_filtered() {
        let t0 = Instant::now();
        let mut r = reloader();
        let req = r.poll(t0).expect("first");
        r.report(
            Report {
                id: req.id,
                outcome: generation(&req.settings, &[], 1),
            },
            t0,
        );
        assert!(!r.file_event(&["other.lua"], ms(t0, 100)), "not watched");
        assert!(r.poll(ms(t0, 200)).is_none());
        assert!(r.file_event(&["tree.lua"], ms(t0, 100)));
        assert!(
            r.file_event(&["tree.lua"], ms(t0, 130)),
            "a second write of the same save"
        );
        assert_eq!(r.next_wake(), Some(ms(t0, 180)));
        assert!(r.poll(ms(t0, 170)).is_none(), "still settling");
        let req = r.poll(ms(t0, 180)).expect("settled");
        assert!(r.poll(ms(t0, 400)).is_none(), "only once");
        r.report(
            Report {
                id: req.id,
                outcome: generation(&req.settings, &[], 2),
            },
            ms(t0, 300),
        );
        assert_eq!(r.last_latency(), Some(Duration::from_millis(170)));
        assert_eq!(r.current_trigger(), Some(ms(t0, 130)));
    }

    #[test]
    fn a_newer_save_cancels_and_supersedes_the_running_generation() {
        let t0 = Instant::now();
        let mut r = reloader();
        let first = r.poll(t0).expect("first");
        r.file_event(&["tree.lua"], ms(t0, 10));
        let second = r.poll(ms(t0, 60)).expect("superseding");
        assert!(
            first.cancel.load(Ordering::Relaxed),
            "the old run is told to stop"
        );
        assert!(!second.cancel.load(Ordering::Relaxed));
        assert!(second.id > first.id);
        // The old run's late answer is ignored, even a successful one.
        assert!(!r.report(
            Report {
                id: first.id,
                outcome: generation(&first.settings, &[], 1)
            },
            t0
        ));
        assert!(r.current().is_none());
        assert!(r.is_running());
        assert!(r.report(
            Report {
                id: second.id,
                outcome: generation(&second.settings, &[], 2)
            },
            t0
        ));
        assert_eq!(r.current().map(|g| g.model.stats.nodes), Some(2));
    }

    #[test]
    fn errors_keep_the_last_good_model_until_fixed() {
        let t0 = Instant::now();
        let mut r = reloader();
        let req = r.poll(t0).expect("first");
        r.report(
            Report {
                id: req.id,
                outcome: generation(&req.settings, &["mod.lua"], 5),
            },
            t0,
        );
        r.file_event(&["mod.lua"], ms(t0, 10));
        let req = r.poll(ms(t0, 100)).expect("module changed");
        let failed = Outcome::Failed {
            message: "mod.lua:3: boom".into(),
            loaded: vec![],
        };
        assert!(!r.report(
            Report {
                id: req.id,
                outcome: failed
            },
            t0
        ));
        assert_eq!(r.status(), &Status::Error("mod.lua:3: boom".into()));
        assert_eq!(
            r.current().map(|g| g.model.stats.nodes),
            Some(5),
            "last good model stays"
        );
        assert!(
            r.watched().contains(Path::new("mod.lua")),
            "the fix may come in the module"
        );
        r.file_event(&["mod.lua"], ms(t0, 200));
        let req = r.poll(ms(t0, 300)).expect("fixed");
        assert_eq!(
            r.status(),
            &Status::Error("mod.lua:3: boom".into()),
            "shown until fixed"
        );
        r.report(
            Report {
                id: req.id,
                outcome: generation(&req.settings, &["mod.lua"], 6),
            },
            t0,
        );
        assert_eq!(r.status(), &Status::Ready);
        assert_eq!(r.current().map(|g| g.model.stats.nodes), Some(6));
    }

    #[test]
    fn a_deleted_script_is_gone_until_it_comes_back() {
        let t0 = Instant::now();
        let mut r = reloader();
        let req = r.poll(t0).expect("first");
        r.report(
            Report {
                id: req.id,
                outcome: generation(&req.settings, &[], 5),
            },
            t0,
        );
        r.file_event(&["tree.lua"], ms(t0, 10));
        let req = r.poll(ms(t0, 100)).expect("deleted");
        r.report(
            Report {
                id: req.id,
                outcome: Outcome::Gone,
            },
            t0,
        );
        assert_eq!(r.status(), &Status::Gone);
        assert!(r.current().is_some());
        assert!(r.poll(ms(t0, 1000)).is_none(), "waits");
        r.file_event(&["tree.lua"], ms(t0, 2000));
        let req = r.poll(ms(t0, 2100)).expect("back");
        r.report(
            Report {
                id: req.id,
                outcome: generation(&req.settings, &[], 9),
            },
            t0,
        );
        assert_eq!(r.status(), &Status::Ready);
    }

    #[test]
    fn panel_changes_wait_for_the_running_generation_and_coalesce() {
        let t0 = Instant::now();
        let mut r = reloader();
        let first = r.poll(t0).expect("first");
        let mut s = r.settings().clone();
        s.set_param("height", "3".into());
        r.set_settings(s.clone());
        s.set_param("height", "4".into());
        s.seed = 9;
        r.set_settings(s.clone());
        assert!(
            r.poll(ms(t0, 10)).is_none(),
            "a slider does not cancel the run"
        );
        assert!(!first.cancel.load(Ordering::Relaxed));
        r.report(
            Report {
                id: first.id,
                outcome: generation(&first.settings, &[], 1),
            },
            t0,
        );
        let next = r.poll(ms(t0, 20)).expect("latest settings");
        assert_eq!(
            next.settings.params,
            vec![("height".to_string(), "4".to_string())]
        );
        assert_eq!(next.settings.seed, 9);
        r.report(
            Report {
                id: next.id,
                outcome: generation(&next.settings, &[], 1),
            },
            t0,
        );
        r.set_settings(s);
        assert!(r.poll(ms(t0, 30)).is_none(), "same settings: nothing to do");
    }

    #[test]
    fn a_syntax_error_at_start_is_shown_without_a_model() {
        let t0 = Instant::now();
        let mut r = reloader();
        let req = r.poll(t0).expect("first");
        let failed = Outcome::Failed {
            message: "tree.lua:1: syntax error".into(),
            loaded: vec![],
        };
        r.report(
            Report {
                id: req.id,
                outcome: failed,
            },
            t0,
        );
        assert!(r.current().is_none());
        assert_eq!(
            r.status(),
            &Status::Error("tree.lua:1: syntax error".into())
        );
    }
}
