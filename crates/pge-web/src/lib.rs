//! PGE in a browser: a script's glb from its text and parameters, the script library bundled
//! in memory so that `require`, `pge.load` and species paths resolve as they do beside the
//! repository's `scripts/`.
//!
//! The same code runs natively (its tests) and as WebAssembly (`wasm32-unknown-emscripten`,
//! whose entry points are in `main.rs`): it reads no file and no system clock of its own, and
//! it makes the same bytes as `pge run` for the same script, seed and parameters.

use std::path::Path;
use std::time::Duration;

use pge_engine::files::MemoryFiles;
use pge_engine::{Engine, Error, SessionOptions};
use serde::Deserialize;
use serde_json::{Map, Value, json};

/// The repository's `scripts/` folder, every file under its path from the repository.
const LIBRARY: &[(&str, &[u8])] = include!(concat!(env!("OUT_DIR"), "/library.rs"));

/// Where an edited script lives when the request names no path: beside the library's own
/// folders, so `require("examples.lib.box")` and `../species/oak.lua` resolve.
pub const DEFAULT_PATH: &str = "scripts/playground.lua";

/// The library's files in memory, under `/scripts/...` (the working folder is `/`, so they
/// are shown as `scripts/...`, as when `pge run` runs in the repository).
#[must_use]
pub fn library_files() -> MemoryFiles {
    let mut files = MemoryFiles::new();
    for (path, bytes) in LIBRARY {
        files.insert(path, *bytes);
    }
    files
}

/// The library's Lua scripts (not the modules under `lib/` folders): path and text, in order.
#[must_use]
pub fn library_scripts() -> Vec<(&'static str, &'static str)> {
    LIBRARY
        .iter()
        .filter(|(path, _)| path.ends_with(".lua") && !path.contains("/lib/"))
        .filter_map(|(path, bytes)| Some((*path, std::str::from_utf8(bytes).ok()?)))
        .collect()
}

/// What to generate: a script (its text, or a library script by its path), seed,
/// parameter overrides and limits. Read from JSON with camelCase names.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Request {
    /// The script's path (`scripts/species/oak.lua`): the text of the library script there
    /// unless `source` is given, which then takes its place. Default [`DEFAULT_PATH`].
    #[serde(default)]
    pub path: Option<String>,
    /// The script's text.
    #[serde(default)]
    pub source: Option<String>,
    /// The seed (default 1, as `pge run`).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Overrides of declared parameters (`--set NAME=VALUE`): numbers, booleans or text.
    #[serde(default)]
    pub params: Map<String, Value>,
    /// The time limit in seconds (default 300, as `pge run`).
    #[serde(default)]
    pub time_limit: Option<f64>,
    /// The memory limit in MiB (default [`DEFAULT_MEMORY_MIB`]).
    #[serde(default)]
    pub memory_limit_mib: Option<usize>,
    /// The instruction limit (default none, as `pge run`).
    #[serde(default)]
    pub instruction_limit: Option<u64>,
}

fn default_seed() -> u64 {
    1
}

/// The memory limit of a page's run: the desktop's 4096 MiB is all a 32-bit WebAssembly
/// memory can address, so the Lua state and the plugins' buffers get half of it.
pub const DEFAULT_MEMORY_MIB: usize = 2048;

/// The time limit of a run when the request gives none (`pge run`'s default).
pub const DEFAULT_TIME_LIMIT: f64 = 300.0;

/// A generated model: the glb and what the page shows of it.
#[derive(Debug)]
pub struct Output {
    /// The glb, byte for byte what `pge run` writes.
    pub glb: Vec<u8>,
    /// `{"triangles", "vertices", "leaves", "nodes", "seconds", "params": [...],
    /// "warnings": [...]}`; each param `{"name", "value", "default", "min", "max", "doc"}`.
    pub info: Value,
}

/// Why nothing was generated: the message (`FILE:LINE: message`) and, when known, the file
/// and line to mark.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The whole message, as `pge run` prints it.
    pub message: String,
    /// The script the error is in (`scripts/playground.lua`).
    pub file: Option<String>,
    /// Its 1-based line.
    pub line: Option<u32>,
}

impl Failure {
    /// The failure as JSON: `{"error", "file", "line"}`.
    #[must_use]
    pub fn to_json(&self) -> Value {
        json!({"error": self.message, "file": self.file, "line": self.line})
    }
}

impl From<Error> for Failure {
    fn from(e: Error) -> Failure {
        let location = e.location().cloned();
        Failure {
            message: e.to_string(),
            file: location.as_ref().map(|l| l.file.clone()),
            line: location.and_then(|l| l.line),
        }
    }
}

impl From<String> for Failure {
    fn from(message: String) -> Failure {
        Failure {
            message,
            file: None,
            line: None,
        }
    }
}

/// An engine with every PGE plugin (`pge_plugins::with_all`, as `pge` has them), reading `files`.
#[must_use]
pub fn engine_builder(files: MemoryFiles) -> pge_engine::EngineBuilder {
    pge_plugins::with_all(
        Engine::builder().files(files).library("/scripts"),
        pge_plugins::pge_forest::ForestPlugin::default(),
    )
}

/// A parameter override as `--set` gives it: the text of a number, boolean or string.
fn override_text(value: &Value) -> String {
    match value {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Runs the request's script and grows it: the glb and its statistics, or why not.
pub fn generate(request: &Request) -> Result<Output, Failure> {
    let path = request.path.as_deref().unwrap_or(DEFAULT_PATH);
    let mut files = library_files();
    if let Some(source) = &request.source {
        files.insert(path, source.as_bytes().to_vec());
    }
    let time = request.time_limit.unwrap_or(DEFAULT_TIME_LIMIT);
    if !(time.is_finite() && time > 0.0) {
        return Err(
            format!("the time limit must be a positive number of seconds, not {time}").into(),
        );
    }
    let engine = engine_builder(files)
        .time_limit(Some(Duration::from_secs_f64(time)))
        .memory_limit_mib(request.memory_limit_mib.unwrap_or(DEFAULT_MEMORY_MIB))
        .instruction_limit(request.instruction_limit)
        .build()?;
    let session = engine.session(SessionOptions {
        seed: request.seed,
        params: request
            .params
            .iter()
            .map(|(k, v)| (k.clone(), override_text(v)))
            .collect(),
        steps: None,
        ..SessionOptions::default()
    })?;
    let generated = session.generate(Path::new(path), &mut |_, _| {})?;
    let model = &generated.model;
    let meta = pge_engine::export::ExportMeta {
        seed: request.seed,
        params: generated
            .params
            .iter()
            .map(|p| (p.name.clone(), p.value.to_json()))
            .collect(),
    };
    let glb = pge_engine::export::glb_bytes(model, &meta)?;
    let params: Vec<Value> = generated
        .params
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "value": p.value.to_json(),
                "default": p.default.to_json(),
                "min": p.min,
                "max": p.max,
                "doc": p.doc,
            })
        })
        .collect();
    let vertices: usize = model.meshes.iter().map(|m| m.vertex_count()).sum();
    let info = json!({
        "triangles": model.triangle_count(),
        "vertices": vertices,
        "leaves": model.stats.leaves,
        "nodes": model.stats.nodes,
        "seconds": generated.seconds,
        "params": params,
        "warnings": model.stats.warnings,
    });
    Ok(Output { glb, info })
}

/// [`generate`] of a request in JSON; a request that does not parse is a failure too.
pub fn generate_json(request: &str) -> Result<Output, Failure> {
    let request: Request = serde_json::from_str(request)
        .map_err(|e| Failure::from(format!("the request is not valid: {e}")))?;
    generate(&request)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(json: Value) -> Request {
        serde_json::from_value(json).expect("a request")
    }

    #[test]
    fn the_library_is_bundled_with_its_data_files() {
        let scripts = library_scripts();
        assert!(scripts.iter().any(|(p, _)| *p == "scripts/species/oak.lua"));
        assert!(!scripts.iter().any(|(p, _)| p.contains("/lib/")));
        let files = library_files();
        assert!(
            files
                .paths()
                .any(|p| p == Path::new("/scripts/species/data/crown.obj"))
        );
    }

    #[test]
    fn the_plugins_are_those_of_the_pge_command() {
        let names = |e: &Engine| {
            e.plugins()
                .map(|p| p.name().to_string())
                .collect::<Vec<_>>()
        };
        let web = engine_builder(MemoryFiles::new()).build().expect("engine");
        let native = pge::default_engine().build().expect("engine");
        assert_eq!(names(&web), names(&native));
    }

    #[test]
    fn an_edited_script_requires_library_modules_and_reports_its_line() {
        let source = "local box = require(\"examples.lib.box\")\nreturn pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n";
        let out = generate(&request(json!({"source": source}))).expect("generates");
        assert_eq!(&out.glb[..4], b"glTF");
        assert_eq!(out.info["triangles"], 1);
        let failure = generate(&request(json!({"source": "local x = 1\nerror('boom')\n"})))
            .expect_err("fails");
        assert_eq!(failure.file.as_deref(), Some(DEFAULT_PATH));
        assert_eq!(failure.line, Some(2));
        assert!(
            failure.message.starts_with("scripts/playground.lua:2:"),
            "{}",
            failure.message
        );
    }

    #[test]
    fn a_script_reads_library_data_but_writes_no_file() {
        let read = "local img = pge.Image.load(\"modellers/explorers_map.png\")\nreturn pge.mesh{ positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2} }\n";
        generate(&request(json!({"source": read}))).expect("reads the bundled image");
        let write = "local img = pge.Image.new(4, 4)\nimg:save(\"out.png\")\n";
        let failure = generate(&request(json!({"source": write}))).expect_err("refused");
        assert!(
            failure.message.contains("cannot write 'out.png'"),
            "{}",
            failure.message
        );
        assert_eq!(failure.line, Some(2));
    }

    #[test]
    fn a_slow_script_is_stopped_by_the_time_limit() {
        let failure = generate(&request(
            json!({"source": "while true do end", "timeLimit": 0.2}),
        ))
        .expect_err("stopped");
        assert!(
            failure.message.contains("time limit"),
            "{}",
            failure.message
        );
        assert_eq!(failure.line, Some(1));
    }

    #[test]
    fn parameters_are_overridden_and_reported() {
        let source = "local p = pge.params{ n = {3, min = 1, max = 8} }\nlocal pos, idx = {}, {}\nfor i = 0, p.n - 1 do\n  for _, v in ipairs{i,0,0, i+1,0,0, i,1,0} do pos[#pos+1] = v end\n  for k = 0, 2 do idx[#idx+1] = 3*i + k end\nend\nreturn pge.mesh{ positions = pos, indices = idx }\n";
        let out =
            generate(&request(json!({"source": source, "params": {"n": 5}}))).expect("generates");
        assert_eq!(out.info["triangles"], 5);
        assert_eq!(out.info["params"][0]["name"], "n");
        assert_eq!(out.info["params"][0]["value"], 5);
        assert_eq!(out.info["params"][0]["max"], 8.0);
        let bad = generate_json(r#"{"source": "return 1", "seeds": 2}"#).expect_err("refused");
        assert!(bad.message.contains("seeds"), "{}", bad.message);
    }
}
