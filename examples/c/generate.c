/* Generates a PGE script's glb through the C API and writes it to a file.
 *
 *     generate SCRIPT OUT.glb [PARAMS_JSON [SEED [TIMES]]]
 *
 * OUT.glb holds the bytes `pge run SCRIPT -o OUT.glb --set ... --seed SEED` writes. TIMES
 * (default 1) generates that many times, freeing each result: a leak checker's loop. The
 * library folder is $PGE_LIBRARY, or found as `pge run` finds it. Exits 1 with
 * `FILE:LINE: message` on stderr when the script fails. */
#include <stdio.h>
#include <stdlib.h>

#include "pge.h"

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s SCRIPT OUT.glb [PARAMS_JSON [SEED [TIMES]]]\n", argv[0]);
        return 2;
    }
    const char *params = argc > 3 ? argv[3] : NULL;
    uint64_t seed = argc > 4 ? strtoull(argv[4], NULL, 10) : 1;
    long times = argc > 5 ? strtol(argv[5], NULL, 10) : 1;

    PgeEngine *engine = pge_engine_new(NULL);
    if (engine == NULL) {
        fprintf(stderr, "%s\n", pge_last_error());
        return 1;
    }
    uint8_t *glb = NULL;
    size_t len = 0;
    for (long i = 0; i < times; i++) {
        pge_bytes_free(glb, len);
        PgeStatus status = pge_generate(engine, argv[1], params, seed, &glb, &len);
        if (status != PGE_OK) {
            fprintf(stderr, "%s\n", pge_last_error());
            pge_engine_free(engine);
            return 1;
        }
    }
    FILE *out = fopen(argv[2], "wb");
    int failed = out == NULL || fwrite(glb, 1, len, out) != len;
    if (out != NULL && fclose(out) != 0) {
        failed = 1;
    }
    if (failed) {
        fprintf(stderr, "cannot write %s\n", argv[2]);
    }
    pge_bytes_free(glb, len);
    pge_engine_free(engine);
    return failed;
}
