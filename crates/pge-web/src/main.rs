//! The WebAssembly module's entry points, called from JavaScript (`web/src/engine.js`):
//!
//! - `pge_web_generate(request)`: a request in JSON (see [`pge_web::Request`]); 0 when a
//!   model was made, 1 when not. Then `pge_web_info()` is the JSON of its statistics or of
//!   the failure (`{"error", "file", "line"}`), and `pge_web_glb()`/`pge_web_glb_len()` the
//!   glb's bytes (none after a failure), valid until the next call.
//! - `pge_web_library()`: the library's scripts as JSON, `[[path, text], ...]`.
//!
//! The clock is the page's (`performance.now()`, through `emscripten_get_now`); the work runs
//! on this one thread (rayon's pool is this thread alone); a panic comes back as a failure.
#![allow(unsafe_code)]

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

use pge_web::{Failure, Output};

#[derive(Default)]
struct Last {
    info: CString,
    glb: Vec<u8>,
}

thread_local! {
    static LAST: RefCell<Last> = RefCell::new(Last::default());
    static LIBRARY: CString = CString::new(
        serde_json::to_string(&pge_web::library_scripts()).unwrap_or_default()
    ).unwrap_or_default();
}

#[cfg(target_os = "emscripten")]
unsafe extern "C" {
    /// Milliseconds from the page's clock (`performance.now()`).
    fn emscripten_get_now() -> f64;
}

#[cfg(target_os = "emscripten")]
fn page_clock() -> std::time::Duration {
    // SAFETY: a plain call into emscripten's runtime, no arguments, no memory shared.
    let ms = unsafe { emscripten_get_now() };
    std::time::Duration::from_secs_f64(ms.max(0.0) / 1000.0)
}

/// The page's clock and a pool of this one thread, set once before the first run.
fn setup() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        #[cfg(target_os = "emscripten")]
        {
            pge_engine::clock::set_clock(page_clock);
            // No threads here: the calling thread is the pool's only worker, so parallel
            // work runs in order on it (the same bytes for any number of threads).
            let _ = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .use_current_thread()
                .build_global();
        }
    });
}

/// Generates `request` (JSON): the statistics and glb, or the failure (a panic included).
fn run(request: &str) -> Result<Output, Failure> {
    setup();
    catch_unwind(AssertUnwindSafe(|| pge_web::generate_json(request))).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".into());
        Err(Failure::from(format!(
            "internal error (a bug in PGE): {what}"
        )))
    })
}

/// Generates the request at `request` (a C string of JSON); 0 when a model was made.
///
/// # Safety
/// `request` is null or a NUL-terminated string in the module's memory (JavaScript's
/// `ccall` with a `string` argument passes one).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pge_web_generate(request: *const c_char) -> i32 {
    let text = if request.is_null() {
        String::new()
    } else {
        // SAFETY: JavaScript passes a NUL-terminated string it allocated (`stringToUTF8`).
        unsafe { CStr::from_ptr(request) }
            .to_string_lossy()
            .into_owned()
    };
    let (status, info, glb) = match run(&text) {
        Ok(out) => (0, out.info, out.glb),
        Err(failure) => (1, failure.to_json(), Vec::new()),
    };
    LAST.with_borrow_mut(|last| {
        last.info = CString::new(info.to_string()).unwrap_or_default();
        last.glb = glb;
    });
    status
}

/// The JSON of the last run's statistics or failure.
#[unsafe(no_mangle)]
pub extern "C" fn pge_web_info() -> *const c_char {
    LAST.with_borrow(|last| last.info.as_ptr())
}

/// The last run's glb.
#[unsafe(no_mangle)]
pub extern "C" fn pge_web_glb() -> *const u8 {
    LAST.with_borrow(|last| last.glb.as_ptr())
}

/// The length of the last run's glb.
#[unsafe(no_mangle)]
pub extern "C" fn pge_web_glb_len() -> usize {
    LAST.with_borrow(|last| last.glb.len())
}

/// The library's scripts: `[[path, text], ...]`.
#[unsafe(no_mangle)]
pub extern "C" fn pge_web_library() -> *const c_char {
    LIBRARY.with(|l| l.as_ptr())
}

/// The module's start: nothing to do until the page calls.
fn main() {}
