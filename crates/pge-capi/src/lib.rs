//! PGE's C API: create an engine (its script library), generate a script with parameters
//! (JSON) and a seed into the `.glb` bytes `pge run` writes, read the last error
//! (`FILE:LINE: message`), free what was returned. `include/pge.h` is this file's header,
//! made by cbindgen (`crates/pge-capi/cbindgen.toml`).
//!
//! Every function may be called from any thread; an engine may be shared by threads (it is
//! immutable), each generation runs on its own. No panic crosses the boundary: one is caught
//! and reported as an error.

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

/// An engine: where its script library is. Made by [`pge_engine_new`], freed by
/// [`pge_engine_free`].
pub struct PgeEngine {
    library: Option<PathBuf>,
}

/// What [`pge_generate`] returns.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PgeStatus {
    /// The glb was made.
    PgeOk = 0,
    /// The script failed (or a file could not be read): see [`pge_last_error`].
    PgeScriptError = 1,
    /// The run went past its time limit.
    PgeTimeLimit = 2,
    /// The run went past its memory limit.
    PgeMemoryLimit = 3,
    /// The script went past its instruction budget.
    PgeInstructionLimit = 4,
    /// A wrong argument (a null pointer, parameters that are not a JSON object, ...).
    PgeInvalidArgument = 5,
    /// A bug in PGE (a panic, caught).
    PgeInternalError = 6,
}

thread_local! {
    static LAST_ERROR: RefCell<Option<CString>> = const { RefCell::new(None) };
}

fn set_error(message: &str) {
    // A message with a NUL byte is cut there.
    let text = message.split('\0').next().unwrap_or_default();
    let text = CString::new(text).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = Some(text));
}

/// `text` as a str, or an error naming `what`.
///
/// # Safety
/// `text` is null or a NUL-terminated string.
unsafe fn text<'a>(text: *const c_char, what: &str) -> Result<&'a str, String> {
    if text.is_null() {
        return Err(format!("{what} is NULL"));
    }
    // SAFETY: the caller passes a NUL-terminated string.
    unsafe { CStr::from_ptr(text) }
        .to_str()
        .map_err(|_| format!("{what} is not UTF-8"))
}

/// `--set` overrides from a JSON object of numbers, booleans and strings.
fn overrides(json: &str) -> Result<Vec<(String, String)>, String> {
    if json.trim().is_empty() {
        return Ok(Vec::new());
    }
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| format!("params: not JSON: {e}"))?;
    let serde_json::Value::Object(map) = value else {
        return Err("params: a JSON object of name -> value is needed".into());
    };
    map.into_iter()
        .map(|(name, value)| {
            let text = match value {
                serde_json::Value::Number(n) => n.to_string(),
                serde_json::Value::Bool(b) => b.to_string(),
                serde_json::Value::String(s) => s,
                other => {
                    return Err(format!(
                        "params: {name}: a number, boolean or string, not {other}"
                    ));
                }
            };
            Ok((name, text))
        })
        .collect()
}

/// A new engine whose script library is the folder `library` (NULL: found as `pge run`
/// finds it: `$PGE_LIBRARY`, or a marked `scripts/` folder above the current one). NULL on
/// failure, with [`pge_last_error`] set. Free it with [`pge_engine_free`].
///
/// # Safety
/// `library` is NULL or a NUL-terminated UTF-8 string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pge_engine_new(library: *const c_char) -> *mut PgeEngine {
    let made = catch_unwind(|| -> Result<PgeEngine, String> {
        let library = if library.is_null() {
            None
        } else {
            // SAFETY: the caller passes a NUL-terminated string.
            Some(PathBuf::from(unsafe { text(library, "library") }?))
        };
        Ok(PgeEngine { library })
    });
    match made {
        Ok(Ok(engine)) => Box::into_raw(Box::new(engine)),
        Ok(Err(message)) => {
            set_error(&message);
            std::ptr::null_mut()
        }
        Err(_) => {
            set_error("internal error: a panic in pge_engine_new");
            std::ptr::null_mut()
        }
    }
}

/// Frees an engine of [`pge_engine_new`] (NULL: nothing).
///
/// # Safety
/// `engine` is NULL or an engine of [`pge_engine_new`] not yet freed, used by no other
/// thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pge_engine_free(engine: *mut PgeEngine) {
    if !engine.is_null() {
        // SAFETY: made by Box::into_raw in pge_engine_new, freed once.
        drop(unsafe { Box::from_raw(engine) });
    }
}

/// Runs the script `script` with `params_json` (a JSON object of name -> number, boolean
/// or string overriding what it declares with `pge.params`; NULL or "" for none) and
/// `seed`, and sets `*glb` and `*len` to the `.glb` bytes `pge run SCRIPT --set ... --seed
/// SEED` writes (free them with [`pge_bytes_free`]). On failure, `*glb` is NULL, `*len` 0,
/// and [`pge_last_error`] says why (`FILE:LINE: message` for a script's error).
///
/// # Safety
/// `engine` is an engine of [`pge_engine_new`]; `script` and `params_json` are NULL or
/// NUL-terminated strings; `glb` and `len` point to writable memory.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pge_generate(
    engine: *const PgeEngine,
    script: *const c_char,
    params_json: *const c_char,
    seed: u64,
    glb: *mut *mut u8,
    len: *mut usize,
) -> PgeStatus {
    if glb.is_null() || len.is_null() {
        set_error("glb and len must not be NULL");
        return PgeStatus::PgeInvalidArgument;
    }
    // SAFETY: the caller passes writable pointers (checked non-null above).
    unsafe {
        *glb = std::ptr::null_mut();
        *len = 0;
    }
    let run = catch_unwind(AssertUnwindSafe(
        || -> Result<Vec<u8>, (PgeStatus, String)> {
            let invalid = |m: String| (PgeStatus::PgeInvalidArgument, m);
            if engine.is_null() {
                return Err(invalid("engine is NULL".into()));
            }
            // SAFETY: the caller passes an engine of pge_engine_new.
            let engine = unsafe { &*engine };
            // SAFETY: the caller passes NUL-terminated strings.
            let script = unsafe { text(script, "script") }.map_err(invalid)?;
            let params = if params_json.is_null() {
                Vec::new()
            } else {
                // SAFETY: as above.
                overrides(unsafe { text(params_json, "params_json") }.map_err(invalid)?)
                    .map_err(invalid)?
            };
            let mut request = pge::Request::new(pge::Script::File(script.into()));
            request.params = params;
            request.seed = seed;
            request.library = engine.library.clone();
            pge::generate(&request).map(|g| g.glb).map_err(|e| {
                let status = match e.kind() {
                    pge::ErrorKind::TimeLimit => PgeStatus::PgeTimeLimit,
                    pge::ErrorKind::MemoryLimit => PgeStatus::PgeMemoryLimit,
                    pge::ErrorKind::InstructionLimit => PgeStatus::PgeInstructionLimit,
                    pge::ErrorKind::Argument => PgeStatus::PgeInvalidArgument,
                    _ => PgeStatus::PgeScriptError,
                };
                (status, e.to_string())
            })
        },
    ));
    match run {
        Ok(Ok(bytes)) => {
            let bytes = bytes.into_boxed_slice();
            let n = bytes.len();
            // SAFETY: writable pointers, checked above.
            unsafe {
                *len = n;
                *glb = Box::into_raw(bytes).cast::<u8>();
            }
            PgeStatus::PgeOk
        }
        Ok(Err((status, message))) => {
            set_error(&message);
            status
        }
        Err(_) => {
            set_error("internal error: a panic in pge_generate");
            PgeStatus::PgeInternalError
        }
    }
}

/// Frees bytes of [`pge_generate`] (NULL: nothing).
///
/// # Safety
/// `glb` and `len` are what one call of [`pge_generate`] set, not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pge_bytes_free(glb: *mut u8, len: usize) {
    if !glb.is_null() {
        // SAFETY: made by Box::into_raw of a boxed slice of `len` bytes in pge_generate.
        drop(unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(glb, len)) });
    }
}

/// The last error of this thread (`FILE:LINE: message` for a script's), or NULL when none
/// happened yet. Valid until the next failing call on this thread; not to be freed.
#[unsafe(no_mangle)]
pub extern "C" fn pge_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ref().map_or(std::ptr::null(), |s| s.as_ptr()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_are_a_json_object_of_plain_values() {
        let set = overrides(r#"{"height": 4.5, "n": 3, "flag": true, "name": "x"}"#);
        let set = set.expect("parses");
        assert_eq!(
            set,
            [
                ("height".to_string(), "4.5".to_string()),
                ("n".into(), "3".into()),
                ("flag".into(), "true".into()),
                ("name".into(), "x".into()),
            ]
        );
        assert!(overrides("[1]").is_err());
        assert!(overrides(r#"{"a": [1]}"#).is_err());
        assert!(overrides("").expect("none").is_empty());
    }
}
