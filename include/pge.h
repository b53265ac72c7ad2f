#ifndef PGE_H
#define PGE_H

/* Made by cbindgen from crates/pge-capi/src/lib.rs: do not edit. */

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

// What [`pge_generate`] returns.
typedef enum PgeStatus {
  // The glb was made.
  PGE_OK = 0,
  // The script failed (or a file could not be read): see [`pge_last_error`].
  PGE_SCRIPT_ERROR = 1,
  // The run went past its time limit.
  PGE_TIME_LIMIT = 2,
  // The run went past its memory limit.
  PGE_MEMORY_LIMIT = 3,
  // The script went past its instruction budget.
  PGE_INSTRUCTION_LIMIT = 4,
  // A wrong argument (a null pointer, parameters that are not a JSON object, ...).
  PGE_INVALID_ARGUMENT = 5,
  // A bug in PGE (a panic, caught).
  PGE_INTERNAL_ERROR = 6,
} PgeStatus;

// An engine: where its script library is. Made by [`pge_engine_new`], freed by
// [`pge_engine_free`].
typedef struct PgeEngine PgeEngine;

#ifdef __cplusplus
extern "C" {
#endif // __cplusplus

// A new engine whose script library is the folder `library` (NULL: found as `pge run`
// finds it: `$PGE_LIBRARY`, or a marked `scripts/` folder above the current one). NULL on
// failure, with [`pge_last_error`] set. Free it with [`pge_engine_free`].
//
// # Safety
// `library` is NULL or a NUL-terminated UTF-8 string.
struct PgeEngine *pge_engine_new(const char *library);

// Frees an engine of [`pge_engine_new`] (NULL: nothing).
//
// # Safety
// `engine` is NULL or an engine of [`pge_engine_new`] not yet freed, used by no other
// thread.
void pge_engine_free(struct PgeEngine *engine);

// Runs the script `script` with `params_json` (a JSON object of name -> number, boolean
// or string overriding what it declares with `pge.params`; NULL or "" for none) and
// `seed`, and sets `*glb` and `*len` to the `.glb` bytes `pge run SCRIPT --set ... --seed
// SEED` writes (free them with [`pge_bytes_free`]). On failure, `*glb` is NULL, `*len` 0,
// and [`pge_last_error`] says why (`FILE:LINE: message` for a script's error).
//
// # Safety
// `engine` is an engine of [`pge_engine_new`]; `script` and `params_json` are NULL or
// NUL-terminated strings; `glb` and `len` point to writable memory.
enum PgeStatus pge_generate(const struct PgeEngine *engine,
                            const char *script,
                            const char *params_json,
                            uint64_t seed,
                            uint8_t **glb,
                            size_t *len);

// Frees bytes of [`pge_generate`] (NULL: nothing).
//
// # Safety
// `glb` and `len` are what one call of [`pge_generate`] set, not yet freed.
void pge_bytes_free(uint8_t *glb, size_t len);

// The last error of this thread (`FILE:LINE: message` for a script's), or NULL when none
// happened yet. Valid until the next failing call on this thread; not to be freed.
const char *pge_last_error(void);

#ifdef __cplusplus
}  // extern "C"
#endif  // __cplusplus

#endif  /* PGE_H */
