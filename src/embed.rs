//! Generating from a host program: one call from a script (a file, or its text under a name)
//! and its arguments to the `.glb` bytes `pge run` writes for the same arguments, with the
//! statistics `pge run --stats` prints and the warnings. `pge run` itself grows its models
//! through [`Request::grow`], so the bytes are the same by construction.
//!
//! ```no_run
//! let mut request = pge::Request::new(pge::Script::File("scripts/species/oak.lua".into()));
//! request.seed = 7;
//! request.params.push(("height".into(), "12".into()));
//! let generation = pge::generate(&request)?;
//! std::fs::write("oak.glb", &generation.glb)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use pge_engine::export::{ExportMeta, Instancing, glb_bytes_with, glb_stages_bytes};
use pge_engine::geometry::Model;
use pge_engine::{Engine, EngineBuilder, Location, ParamInfo, Session, SessionOptions, Step};
use pge_forest::ForestRun;
use serde_json::Value;

/// The most steps a growth stage may ask for.
pub const STAGE_CAP: u32 = 100_000;

/// The version of PGE (of this library and the `pge` command).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The script of a [`Request`].
#[derive(Clone, Debug)]
pub enum Script {
    /// A script file.
    File(PathBuf),
    /// A script's text, shown as `name` in errors and warnings (`name:LINE: message`); the
    /// folder of `name`, when it exists, is the script's folder for `require` and `pge.load`.
    Source {
        /// The file the text is shown as.
        name: String,
        /// The Lua source.
        text: String,
    },
}

impl Script {
    /// The path the script is shown as.
    #[must_use]
    pub fn shown(&self) -> PathBuf {
        match self {
            Script::File(path) => path.clone(),
            Script::Source { name, .. } => PathBuf::from(name),
        }
    }

    /// Where an error about the whole run points (an export past the time limit): the
    /// script's last `return` line (the value that grows), or the script alone.
    #[must_use]
    pub fn return_location(&self) -> Location {
        return_location(self)
    }

    /// Runs the script as the main script of `session`.
    fn start<'s>(&self, session: &'s Session) -> pge_engine::Result<pge_engine::Started<'s>> {
        match self {
            Script::File(path) => session.start(path),
            Script::Source { name, text } => session.start_source(name, text),
        }
    }
}

/// What to generate and how: the arguments of `pge run` that decide the model.
#[derive(Clone, Debug)]
pub struct Request {
    /// The script.
    pub script: Script,
    /// Overrides of the parameters the script declares with `pge.params` (`--set NAME=VALUE`).
    pub params: Vec<(String, String)>,
    /// The seed of every random draw (`--seed`, 1 by default).
    pub seed: u64,
    /// Steps to run instead of the algorithm's own count (`--steps`).
    pub steps: Option<u32>,
    /// Growth stages, increasing step counts, each a scene of one glb (`--stages`).
    pub stages: Option<Vec<u32>>,
    /// Worker threads for parallel work; `None`: the current rayon pool (every core by
    /// default). The bytes are the same for any count.
    pub threads: Option<usize>,
    /// The wall-clock limit of the script and its algorithm (`--time-limit`, 300 s).
    pub time_limit: Duration,
    /// The memory limit of the Lua state and the plugins' buffers in MiB (`--memory-limit`,
    /// 4096).
    pub memory_limit_mib: usize,
    /// Set from another thread to stop the run ([`ErrorKind::Cancelled`]).
    pub cancel: Option<Arc<AtomicBool>>,
    /// The script library's folder; `None`: found as `pge run` finds it
    /// ([`crate::library_folder`]).
    pub library: Option<PathBuf>,
}

impl Request {
    /// A request for `script` with `pge run`'s defaults.
    #[must_use]
    pub fn new(script: Script) -> Request {
        Request {
            script,
            params: Vec::new(),
            seed: 1,
            steps: None,
            stages: None,
            threads: None,
            time_limit: Duration::from_secs(300),
            memory_limit_mib: 4096,
            cancel: None,
            library: None,
        }
    }

    /// Checks the arguments a host may get wrong (an [`ErrorKind::Argument`]).
    fn check(&self) -> Result<(), Error> {
        if self.time_limit.is_zero() {
            return Err(Error::argument(
                "the time limit must be more than 0 seconds",
            ));
        }
        if self.memory_limit_mib == 0 {
            return Err(Error::argument("the memory limit must be at least 1 MiB"));
        }
        if self.threads == Some(0) {
            return Err(Error::argument("threads must be at least 1"));
        }
        if self.steps.is_some() && self.stages.is_some() {
            return Err(Error::argument("steps and stages exclude each other"));
        }
        Ok(())
    }

    /// `builder` with this request's time and memory limits.
    #[must_use]
    pub fn limits(&self, builder: EngineBuilder) -> EngineBuilder {
        builder
            .time_limit(Some(self.time_limit))
            .memory_limit_mib(self.memory_limit_mib)
    }

    /// The engine of [`crate::default_engine`] with this request's limits and library.
    pub fn engine(&self) -> Result<Engine, Error> {
        self.check()?;
        let mut builder = self.limits(crate::default_engine());
        if let Some(folder) = &self.library {
            builder = builder.library(folder);
        }
        Ok(builder.build()?)
    }

    /// A session of `engine` for this request (seed, parameters, steps, cancel flag; the
    /// last stage's step count with stages).
    pub fn session(&self, engine: &Engine) -> Result<Session, Error> {
        let steps = match &self.stages {
            Some(stages) => stages.last().copied(),
            None => self.steps,
        };
        Ok(engine.session(SessionOptions {
            seed: self.seed,
            params: self.params.clone(),
            steps,
            cancel: self.cancel.clone(),
            ..SessionOptions::default()
        })?)
    }

    /// Runs the script in a session of `engine` and grows its model (or its stages), on the
    /// calling thread's rayon pool; files the script writes (`img:save`) go to
    /// `output_folder` when given. `progress` receives (steps taken, steps planned if known).
    pub fn grow(
        &self,
        engine: &Engine,
        output_folder: Option<&Path>,
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> Result<Grown, Error> {
        self.check()?;
        let session = self.session(engine)?;
        if let Some(dir) = output_folder {
            session.set_output_folder(dir)?;
        }
        if let Some(stages) = &self.stages {
            return self.grow_stages(&session, stages, progress);
        }
        let (model, meta) = self.grow_in(&session, progress)?;
        Ok(Grown {
            models: Models::One(Box::new(model)),
            meta,
            files: session.loaded_files(),
        })
    }

    /// [`Request::grow`] for a request without stages (which it ignores): the model and the
    /// metadata its glb records.
    pub fn grow_model(
        &self,
        engine: &Engine,
        output_folder: Option<&Path>,
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> Result<(Model, ExportMeta), Error> {
        self.check()?;
        let session = self.session(engine)?;
        if let Some(dir) = output_folder {
            session.set_output_folder(dir)?;
        }
        self.grow_in(&session, progress)
    }

    /// Runs the script in `session` and grows its model.
    fn grow_in(
        &self,
        session: &Session,
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> Result<(Model, ExportMeta), Error> {
        let started = self.script.start(session)?;
        let generated = started.grow(pge_engine::GrowOptions::default(), progress)?;
        Ok((generated.model, export_meta(self.seed, &generated.params)))
    }

    /// Runs the script's algorithm once through every stage, keeping the model of each.
    fn grow_stages(
        &self,
        session: &Session,
        stages: &[u32],
        progress: &mut dyn FnMut(u32, Option<u32>),
    ) -> Result<Grown, Error> {
        let shown = self.script.shown();
        let at_return = || return_location(&self.script);
        check_stages(stages).map_err(|m| pge_engine::Error::script(at_return(), m))?;
        let last = stages[stages.len() - 1];
        let mut algorithm = self.script.start(session)?.algorithm()?;
        if algorithm.planned_steps() == Some(0) {
            return Err(pge_engine::Error::script(
                at_return(),
                format!(
                    "--stages needs a step-wise algorithm (an L-system, a space colonization, a \
                     growth, a pge.Algorithm), but the script returned a finished {}",
                    algorithm.name()
                ),
            )
            .into());
        }
        let ctx = session.context();
        progress(0, Some(last));
        algorithm.init(&ctx)?;
        let mut taken = 0u32;
        let mut done = false;
        let mut models = Vec::with_capacity(stages.len());
        for &stage in stages {
            while !done && taken < stage {
                done = algorithm.step(&ctx)? == Step::Done;
                taken += 1;
                progress(taken, Some(last));
            }
            let mut model = algorithm.finish(&ctx)?;
            model.remove_unusable_triangles();
            model.warn_if_empty(&shown);
            models.push((format!("step {stage}"), model));
        }
        Ok(Grown {
            meta: export_meta(self.seed, &session.declared_params()),
            models: Models::Stages(models),
            files: session.loaded_files(),
        })
    }
}

/// What a [`Request`] grew, not yet written.
#[derive(Debug)]
pub struct Grown {
    /// The model, or the model of every stage.
    pub models: Models,
    /// What the glb records: the seed and the parameters' values.
    pub meta: ExportMeta,
    /// Every file the run read (the script, the modules it required, meshes, textures): a
    /// host that regenerates on save watches them.
    pub files: Vec<PathBuf>,
}

/// The model of a run, or of each of its stages.
#[derive(Debug)]
pub enum Models {
    /// One model (boxed: the stages are a vector).
    One(Box<Model>),
    /// The model of each stage, named `step N`.
    Stages(Vec<(String, Model)>),
}

impl Grown {
    /// The warnings of the run (`FILE:LINE: warning: ...`), of every stage in order.
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        match &self.models {
            Models::One(model) => model.stats.warnings.clone(),
            Models::Stages(stages) => stages
                .iter()
                .flat_map(|(_, m)| m.stats.warnings.iter().cloned())
                .collect(),
        }
    }

    /// The `.glb` bytes, a forest's trees written with `instancing`.
    pub fn glb(&self, instancing: Instancing) -> Result<Vec<u8>, Error> {
        Ok(match &self.models {
            Models::One(model) => glb_bytes_with(model, &self.meta, instancing)?,
            Models::Stages(stages) => glb_stages_bytes(stages, &self.meta)?,
        })
    }

    /// Adds the seconds the export took as the `export` phase (stats only: not in the glb).
    pub fn add_export_phase(&mut self, seconds: f64) {
        if let Models::One(model) = &mut self.models {
            model.stats.add_phase("export", seconds);
        }
    }

    /// The statistics `pge run --stats` prints, but for the file (`output`): `seconds` is the
    /// run's wall time.
    #[must_use]
    pub fn stats(&self, seconds: f64) -> Value {
        match &self.models {
            Models::One(model) => model_stats(model, seconds),
            Models::Stages(models) => {
                let list: Vec<Value> = models
                    .iter()
                    .map(|(name, m)| {
                        serde_json::json!({
                            "name": name,
                            "vertices": m.vertex_count(),
                            "triangles": m.triangle_count(),
                            "nodes": m.stats.nodes,
                            "leaves": m.stats.leaves,
                        })
                    })
                    .collect();
                let m = models.last().map(|(_, m)| m);
                serde_json::json!({
                    "vertices": m.map_or(0, Model::vertex_count),
                    "triangles": m.map_or(0, Model::triangle_count),
                    "nodes": m.map_or(0, |m| m.stats.nodes),
                    "leaves": m.map_or(0, |m| m.stats.leaves),
                    "modules": m.map_or(0, |m| m.stats.modules),
                    "instances": m.map_or(0, |m| m.instances.len()),
                    "seconds": seconds,
                    "stages": list,
                })
            }
        }
    }
}

/// The statistics of `model` as `pge run --stats` prints them, but for the file (`output`):
/// `seconds` is the run's wall time.
#[must_use]
pub fn model_stats(m: &Model, seconds: f64) -> Value {
    let phases: serde_json::Map<String, Value> = m
        .stats
        .phases
        .iter()
        .map(|(k, v)| (k.clone(), (*v).into()))
        .collect();
    serde_json::json!({
        "vertices": m.vertex_count() as u64,
        "triangles": m.triangle_count() as u64,
        "nodes": m.stats.nodes,
        "leaves": m.stats.leaves,
        "modules": m.stats.modules,
        "meshes": m.meshes.len(),
        "instances": m.forest.as_ref().map_or(m.instances.len() as u64, |f| f.instances),
        "seconds": seconds,
        "phases": phases,
        "warnings": m.stats.warnings,
    })
}

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

/// What [`generate`] returns.
#[derive(Clone, Debug)]
pub struct Generation {
    /// The `.glb` file: the bytes `pge run` writes for the same arguments.
    pub glb: Vec<u8>,
    /// What `pge run --stats` prints, without `output`.
    pub stats: Value,
    /// The run's warnings, `FILE:LINE: warning: ...` (those `pge run` prints on stderr).
    pub warnings: Vec<String>,
    /// Every file the run read ([`Grown::files`]).
    pub files: Vec<PathBuf>,
}

/// Generates `request`'s model: the glb bytes `pge run` writes for the same arguments
/// (`--instancing gpu`), its statistics and warnings. With `request.threads`, the parallel
/// work runs on a pool of that many threads made for the call.
pub fn generate(request: &Request) -> Result<Generation, Error> {
    let t0 = Instant::now();
    let engine = request.engine()?;
    let run = || -> Result<Generation, Error> {
        let mut grown = request.grow(&engine, None, &mut |_, _| {})?;
        let te = Instant::now();
        let glb = grown.glb(Instancing::Gpu)?;
        grown.add_export_phase(te.elapsed().as_secs_f64());
        Ok(Generation {
            glb,
            stats: grown.stats(t0.elapsed().as_secs_f64()),
            warnings: grown.warnings(),
            files: std::mem::take(&mut grown.files),
        })
    };
    match request.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::argument(format!("cannot start {n} worker threads: {e}")))?
            .install(run),
        None => run(),
    }
}

/// One parameter a script declares with `pge.params`.
pub type Param = ParamInfo;

/// The parameters `request`'s script declares (name, default, value with the request's
/// overrides, min, max, doc), in order: the script runs, its algorithm does not.
pub fn params(request: &Request) -> Result<Vec<Param>, Error> {
    let engine = request.engine()?;
    let session = request.session(&engine)?;
    request.script.start(&session)?;
    Ok(session.declared_params())
}

/// One tile of a forest with `tile = T`: indices along x and z from the -x, -z corner, and
/// its rectangle of ground (x, z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tile {
    /// Index along x.
    pub i: usize,
    /// Index along z.
    pub j: usize,
    /// The corner of least x and z.
    pub min: [f64; 2],
    /// The corner of greatest x and z.
    pub max: [f64; 2],
}

/// The tiles of the forest `request`'s script returns (`pge tiles`): an error for a script
/// that returns something else or a forest without `tile = T`.
pub fn tiles(request: &Request) -> Result<Vec<Tile>, Error> {
    let engine = request.engine()?;
    let session = request.session(&engine)?;
    let value = request.script.start(&session)?.value().clone();
    let mut algorithm = session.algorithm_from(value)?;
    let Some(forest) = ForestRun::of(&mut *algorithm) else {
        return Err(pge_engine::Error::script(
            Location {
                file: request.script.shown().to_string_lossy().replace('\\', "/"),
                line: None,
            },
            "pge tiles needs a script that returns a forest (pge.Forest with tile = T)",
        )
        .into());
    };
    let tiles = forest
        .tiles(&session.context().budget)
        .map_err(|e| forest.engine_error(e))?;
    Ok(tiles
        .iter()
        .map(|t| Tile {
            i: t.i,
            j: t.j,
            min: t.rect.min,
            max: t.rect.max,
        })
        .collect())
}

/// Where an error about the whole run points: the script's last `return` line (the value
/// that grows), or the script alone.
fn return_location(script: &Script) -> Location {
    let file = script.shown().to_string_lossy().replace('\\', "/");
    let text = match script {
        Script::File(path) => std::fs::read_to_string(path).ok(),
        Script::Source { text, .. } => Some(text.clone()),
    };
    let line = text.and_then(|text| {
        text.lines()
            .enumerate()
            .filter(|(_, l)| l.trim_start().starts_with("return"))
            .map(|(i, _)| i as u32 + 1)
            .last()
    });
    Location { file, line }
}

/// Checks a stages list: increasing, within [`STAGE_CAP`].
fn check_stages(stages: &[u32]) -> Result<(), String> {
    if stages.is_empty() {
        return Err("--stages needs at least one step count".into());
    }
    for w in stages.windows(2) {
        if w[1] <= w[0] {
            return Err(format!(
                "--stages must be increasing step counts, got {} after {}",
                w[1], w[0]
            ));
        }
    }
    let last = stages[stages.len() - 1];
    if last > STAGE_CAP {
        return Err(format!(
            "--stages must be step counts between 0 and {STAGE_CAP} (the step cap), got {last}"
        ));
    }
    Ok(())
}

/// What kind of failure an [`Error`] is, for a host that reacts to each differently.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The script failed (syntax, runtime, a bad option or parameter), or a file could not
    /// be read or written.
    Script,
    /// The run went past its time limit.
    TimeLimit,
    /// The run went past its memory limit.
    MemoryLimit,
    /// The Lua code went past its instruction budget.
    InstructionLimit,
    /// The run was stopped through [`Request::cancel`].
    Cancelled,
    /// The request itself is wrong (a limit of 0, no threads, steps with stages).
    Argument,
}

/// Why a [`Request`] failed: an engine error (printed `FILE:LINE: message`, as `pge run`
/// prints it) or a wrong argument.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The engine's error.
    #[error(transparent)]
    Engine(#[from] pge_engine::Error),
    /// A wrong argument of the request.
    #[error("{0}")]
    Argument(String),
}

impl Error {
    fn argument(message: impl Into<String>) -> Error {
        Error::Argument(message.into())
    }

    /// Its kind.
    #[must_use]
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Argument(_) => ErrorKind::Argument,
            Error::Engine(e) => match e {
                pge_engine::Error::TimeLimit { .. } => ErrorKind::TimeLimit,
                pge_engine::Error::MemoryLimit { .. } => ErrorKind::MemoryLimit,
                pge_engine::Error::InstructionLimit { .. } => ErrorKind::InstructionLimit,
                pge_engine::Error::Cancelled { .. } => ErrorKind::Cancelled,
                _ => ErrorKind::Script,
            },
        }
    }

    /// The script file to fix, when known.
    #[must_use]
    pub fn file(&self) -> Option<String> {
        match self {
            Error::Engine(pge_engine::Error::Io { path, .. }) => {
                Some(path.to_string_lossy().replace('\\', "/"))
            }
            Error::Engine(e) => e.location().map(|l| l.file.clone()),
            Error::Argument(_) => None,
        }
    }

    /// The 1-based line to fix, when known.
    #[must_use]
    pub fn line(&self) -> Option<u32> {
        match self {
            Error::Engine(e) => e.location().and_then(|l| l.line),
            Error::Argument(_) => None,
        }
    }

    /// What went wrong, without the place.
    #[must_use]
    pub fn message(&self) -> String {
        match self {
            Error::Engine(pge_engine::Error::Io { source, .. }) => source.to_string(),
            Error::Engine(e) => e.message(),
            Error::Argument(m) => m.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn library(name: &str) -> Script {
        Script::File(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scripts")
                .join(name),
        )
    }

    #[test]
    fn a_script_error_has_its_file_line_and_message() {
        let request = Request::new(Script::Source {
            name: "tree.lua".into(),
            text: "local a = 1\n\nerror('no trunk')".into(),
        });
        let e = generate(&request).expect_err("fails");
        assert_eq!(e.kind(), ErrorKind::Script);
        assert_eq!((e.file().as_deref(), e.line()), (Some("tree.lua"), Some(3)));
        assert!(e.message().ends_with("no trunk"), "{}", e.message());
        assert_eq!(e.to_string(), format!("tree.lua:3: {}", e.message()));
    }

    #[test]
    fn limits_and_cancelling_are_kinds_of_their_own() {
        let mut request = Request::new(Script::Source {
            name: "loop.lua".into(),
            text: "local i = 0\nwhile true do\n  i = i + 1\nend".into(),
        });
        request.time_limit = Duration::from_millis(200);
        let e = generate(&request).expect_err("runs away");
        assert_eq!(e.kind(), ErrorKind::TimeLimit, "{e}");
        assert_eq!(e.file().as_deref(), Some("loop.lua"));
        let cancel = Arc::new(AtomicBool::new(true));
        request.cancel = Some(cancel);
        request.time_limit = Duration::from_secs(300);
        assert_eq!(
            generate(&request).expect_err("cancelled").kind(),
            ErrorKind::Cancelled
        );
        request.memory_limit_mib = 0;
        assert_eq!(
            generate(&request).expect_err("no memory").kind(),
            ErrorKind::Argument
        );
    }

    #[test]
    fn params_and_stages_come_from_the_script() {
        let text = "local p = pge.params{ n = { 3, min = 1, max = 5, doc = 'turns' } }\n\
                    local l = pge.LSystem('s')\n\
                    l:createInstance(function() return pge.turtle{ angle = 90 } end)\n\
                    l:axiom('F')\n\
                    l:rule('F -> F+F')\n\
                    l:iterations(p.n)\n\
                    return l";
        let mut request = Request::new(Script::Source {
            name: "s.lua".into(),
            text: text.into(),
        });
        request.params.push(("n".into(), "4".into()));
        let params = params(&request).expect("params");
        assert_eq!(params.len(), 1);
        let p = &params[0];
        assert_eq!((p.name.as_str(), p.min, p.max), ("n", Some(1.0), Some(5.0)));
        assert_eq!(p.default, pge_engine::ParamValue::Integer(3));
        assert_eq!(p.value, pge_engine::ParamValue::Integer(4));
        assert_eq!(p.doc.as_deref(), Some("turns"));
        request.stages = Some(vec![3, 2]);
        let e = generate(&request).expect_err("decreasing");
        assert_eq!((e.file().as_deref(), e.line()), (Some("s.lua"), Some(7)));
        request.stages = Some(vec![1, 3]);
        let stages = generate(&request).expect("stages");
        assert_eq!(stages.stats["stages"].as_array().map(Vec::len), Some(2));
        assert_eq!(&stages.glb[..4], b"glTF");
    }

    #[test]
    fn the_tiles_of_a_forest_and_an_error_for_anything_else() {
        let e = tiles(&Request::new(library("examples/spiral.lua"))).expect_err("no forest");
        assert!(
            e.to_string()
                .contains("needs a script that returns a forest"),
            "{e}"
        );
        let tiles = tiles(&Request::new(library("forests/plantation.lua"))).expect("tiles");
        // 120 by 80 metres in tiles of 40: 3 by 2.
        assert_eq!(tiles.len(), 6);
        assert_eq!((tiles[5].i, tiles[5].j), (2, 1));
        assert!(tiles[5].max[0] - tiles[5].min[0] > 39.9, "{tiles:?}");
    }
}
