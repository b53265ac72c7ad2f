//! The native half of the `pge` Python module (`pge._pge`): the library's entry point
//! ([`pge::generate`], [`pge::params`], [`pge::tiles`]) with Python's types. The Python half
//! (`python/pge/__init__.py`) defines the exceptions and `Result`, and documents the API.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use pge::pge_engine::ParamValue;
use pge::{ErrorKind, Request, Script};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString};

/// How often a running generation looks for a signal (Ctrl-C) to Python.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// The stack of the thread that generates: a script's recursion gets what the main thread of
/// `pge run` has.
const STACK: usize = 8 << 20;

/// The request of a call: the script (a path, or `source` with `name`) and the overrides.
fn request(
    script: Option<&Bound<'_, PyAny>>,
    source: Option<String>,
    name: Option<String>,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<Request> {
    let script = match (script, source) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "give a script path or source=, not both",
            ));
        }
        (None, None) => return Err(PyTypeError::new_err("a script path or source= is needed")),
        (Some(path), None) => {
            if name.is_some() {
                return Err(PyValueError::new_err("name= goes with source="));
            }
            let path: std::path::PathBuf = path.extract().map_err(|_| {
                PyTypeError::new_err("the script must be a path (str or os.PathLike)")
            })?;
            Script::File(path)
        }
        (None, Some(text)) => Script::Source {
            name: name.unwrap_or_else(|| "<source>".into()),
            text,
        },
    };
    let mut request = Request::new(script);
    if let Some(params) = params.filter(|p| !p.is_none()) {
        let dict = params
            .cast::<PyDict>()
            .map_err(|_| PyTypeError::new_err("params must be a dict of name -> value"))?;
        for (key, value) in dict.iter() {
            let key: String = key
                .extract()
                .map_err(|_| PyTypeError::new_err("parameter names must be str"))?;
            let text = param_text(&key, &value)?;
            request.params.push((key, text));
        }
    }
    Ok(request)
}

/// A parameter's value as `--set` text: bool, int, float or str.
fn param_text(name: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(b.is_true().to_string());
    }
    if value.is_instance_of::<PyInt>() {
        return Ok(value.str()?.to_string());
    }
    if let Ok(f) = value.cast::<PyFloat>() {
        let f = f.value();
        if !f.is_finite() {
            return Err(PyValueError::new_err(format!(
                "parameter {name}: {f} is not a finite number"
            )));
        }
        // Rust's shortest text that reads back as the same double.
        return Ok(format!("{f:?}"));
    }
    if value.is_instance_of::<PyString>() {
        return value.extract::<String>();
    }
    Err(PyTypeError::new_err(format!(
        "parameter {name}: a bool, int, float or str, not {}",
        value.get_type().name()?
    )))
}

/// A whole number in `[min, max]` (a `TypeError` for another type, a `ValueError` outside).
fn whole(what: &str, value: &Bound<'_, PyAny>, min: u64, max: u64) -> PyResult<u64> {
    if !value.is_instance_of::<PyInt>() || value.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{what} must be an int, not {}",
            value.get_type().name()?
        )));
    }
    match value.extract::<u64>() {
        Ok(n) if (min..=max).contains(&n) => Ok(n),
        _ => Err(PyValueError::new_err(format!(
            "{what} must be between {min} and {max}, got {value}"
        ))),
    }
}

/// The Python exception for a library error: `pge.ScriptError` or its subclass for a
/// limit, `KeyboardInterrupt` for a cancelled run, `ValueError` for a wrong argument.
fn py_error(py: Python<'_>, e: &pge::Error) -> PyErr {
    let class = match e.kind() {
        ErrorKind::Argument => return PyValueError::new_err(e.to_string()),
        // Only a signal cancels a run (see `detached`).
        ErrorKind::Cancelled => {
            return pyo3::exceptions::PyKeyboardInterrupt::new_err(e.to_string());
        }
        ErrorKind::TimeLimit => "TimeLimit",
        ErrorKind::MemoryLimit => "MemoryLimit",
        ErrorKind::InstructionLimit => "InstructionLimit",
        _ => "ScriptError",
    };
    let made = py
        .import("pge")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call1((e.message(), e.file(), e.line())));
    match made {
        Ok(value) => PyErr::from_value(value),
        Err(err) => err,
    }
}

/// Runs `work` on a thread of its own with the GIL released, looking for signals every
/// [`SIGNAL_POLL`]: on one (Ctrl-C's `KeyboardInterrupt`), `cancel` is set, the work stops
/// at its next check and the signal's exception is raised.
fn detached<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let (done, finished) = mpsc::channel();
    let (outcome, interrupted) = py.detach(move || {
        let mut interrupted = None;
        let outcome = std::thread::scope(|scope| {
            let spawned = std::thread::Builder::new()
                .name("pge".into())
                .stack_size(STACK)
                .spawn_scoped(scope, move || {
                    let _ = done.send(work());
                });
            if let Err(e) = spawned {
                return Err(format!("cannot start a thread: {e}"));
            }
            loop {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Ok(value) => return Ok(value),
                    Err(mpsc::RecvTimeoutError::Disconnected) => {
                        return Err("the generation stopped without a result".into());
                    }
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                }
                if interrupted.is_none()
                    && let Err(signal) = Python::attach(|py| py.check_signals())
                {
                    interrupted = Some(signal);
                    cancel.store(true, Ordering::Relaxed);
                }
            }
        });
        (outcome, interrupted)
    });
    if let Some(signal) = interrupted {
        return Err(signal);
    }
    outcome.map_err(pyo3::exceptions::PyRuntimeError::new_err)
}

/// What `pge._pge.generate` returns: the glb, the stats as JSON text, the warnings and the
/// files the run read.
type Generated<'py> = (
    Bound<'py, PyBytes>,
    String,
    Vec<String>,
    Vec<std::path::PathBuf>,
);

/// `pge._pge.generate`: (glb bytes, stats as JSON text, warnings, files read).
#[pyfunction]
#[pyo3(signature = (script=None, *, source=None, name=None, params=None, seed=None, steps=None,
    stages=None, threads=None, time_limit=None, memory_limit=None))]
#[allow(clippy::too_many_arguments)]
fn generate<'py>(
    py: Python<'py>,
    script: Option<&Bound<'py, PyAny>>,
    source: Option<String>,
    name: Option<String>,
    params: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    steps: Option<&Bound<'py, PyAny>>,
    stages: Option<&Bound<'py, PyAny>>,
    threads: Option<&Bound<'py, PyAny>>,
    time_limit: Option<&Bound<'py, PyAny>>,
    memory_limit: Option<&Bound<'py, PyAny>>,
) -> PyResult<Generated<'py>> {
    let mut request = request(script, source, name, params)?;
    let some = |v: Option<&Bound<'py, PyAny>>| v.filter(|v| !v.is_none()).cloned();
    if let Some(seed) = some(seed) {
        request.seed = whole("seed", &seed, 0, u64::MAX)?;
    }
    if let Some(steps) = some(steps) {
        request.steps = Some(whole("steps", &steps, 0, u64::from(u32::MAX))? as u32);
    }
    if let Some(stages) = some(stages) {
        let list = stages
            .cast::<PyList>()
            .map_err(|_| PyTypeError::new_err("stages must be a list of ints"))?;
        let mut counts = Vec::with_capacity(list.len());
        for stage in list.iter() {
            counts.push(whole("a stage", &stage, 0, u64::from(u32::MAX))? as u32);
        }
        request.stages = Some(counts);
    }
    if let Some(threads) = some(threads) {
        request.threads = Some(whole("threads", &threads, 1, 1 << 16)? as usize);
    }
    if let Some(limit) = some(time_limit) {
        let seconds: f64 = limit
            .extract()
            .map_err(|_| PyTypeError::new_err("time_limit must be a number of seconds"))?;
        if !(seconds.is_finite() && seconds > 0.0) {
            return Err(PyValueError::new_err(format!(
                "time_limit must be a positive number of seconds, got {seconds}"
            )));
        }
        request.time_limit = Duration::from_secs_f64(seconds);
    }
    if let Some(limit) = some(memory_limit) {
        request.memory_limit_mib = whole("memory_limit (MiB)", &limit, 1, 1 << 40)? as usize;
    }
    let cancel = Arc::new(AtomicBool::new(false));
    request.cancel = Some(cancel.clone());
    let generated = detached(py, &cancel, || pge::generate(&request))?;
    let generation = generated.map_err(|e| py_error(py, &e))?;
    Ok((
        PyBytes::new(py, &generation.glb),
        generation.stats.to_string(),
        generation.warnings,
        generation.files,
    ))
}

/// A parameter's value as a Python object.
fn param_value<'py>(py: Python<'py>, value: &ParamValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        ParamValue::Integer(i) => i.into_pyobject(py)?.into_any(),
        ParamValue::Number(n) => n.into_pyobject(py)?.into_any(),
        ParamValue::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        ParamValue::Text(s) => PyString::new(py, s).into_any(),
    })
}

/// `pge._pge.params`: {name: {"default", "min", "max", "doc"}} in the engine's order.
#[pyfunction]
#[pyo3(signature = (script=None, *, source=None, name=None, params=None))]
fn params<'py>(
    py: Python<'py>,
    script: Option<&Bound<'py, PyAny>>,
    source: Option<String>,
    name: Option<String>,
    params: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = request(script, source, name, params)?;
    let declared = detached(py, &AtomicBool::new(false), || pge::params(&request))?
        .map_err(|e| py_error(py, &e))?;
    let out = PyDict::new(py);
    for p in declared {
        let entry = PyDict::new(py);
        entry.set_item("default", param_value(py, &p.default)?)?;
        entry.set_item("min", p.min)?;
        entry.set_item("max", p.max)?;
        entry.set_item("doc", p.doc)?;
        out.set_item(p.name, entry)?;
    }
    Ok(out)
}

/// `pge._pge.tiles`: [{"i", "j", "min": (x, z), "max": (x, z)}].
#[pyfunction]
#[pyo3(signature = (script=None, *, source=None, name=None, params=None, seed=None))]
fn tiles<'py>(
    py: Python<'py>,
    script: Option<&Bound<'py, PyAny>>,
    source: Option<String>,
    name: Option<String>,
    params: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let mut request = request(script, source, name, params)?;
    if let Some(seed) = seed.filter(|s| !s.is_none()) {
        request.seed = whole("seed", seed, 0, u64::MAX)?;
    }
    let tiles = detached(py, &AtomicBool::new(false), || pge::tiles(&request))?
        .map_err(|e| py_error(py, &e))?;
    let out = PyList::empty(py);
    for t in tiles {
        let entry = PyDict::new(py);
        entry.set_item("i", t.i)?;
        entry.set_item("j", t.j)?;
        entry.set_item("min", (t.min[0], t.min[1]))?;
        entry.set_item("max", (t.max[0], t.max[1]))?;
        out.append(entry)?;
    }
    Ok(out)
}

/// `pge._pge.library`: the script library's folder as `pge run` finds it, or `None`.
#[pyfunction]
fn library() -> Option<std::path::PathBuf> {
    pge::library_folder()
}

/// The native module.
#[pymodule]
fn _pge(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("version", pge::VERSION)?;
    m.add_function(wrap_pyfunction!(library, m)?)?;
    m.add_function(wrap_pyfunction!(generate, m)?)?;
    m.add_function(wrap_pyfunction!(params, m)?)?;
    m.add_function(wrap_pyfunction!(tiles, m)?)?;
    Ok(())
}
