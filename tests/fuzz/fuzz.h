/* Shared by the fuzz harnesses (tests/fuzz/README.md). Each harness defines
 * LLVMFuzzerTestOneInput; libFuzzer drives it (LAHAR_FUZZ=ON, clang), replay_main.c replays a
 * corpus through it in any build. A harness keeps no state from one input to the next. */
#ifndef LAHAR_FUZZ_H
#define LAHAR_FUZZ_H
#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Decode a complete message of frame type `type` (frame_t.MSG_*) as the process that receives
 * it does, and use what it decoded as that process would (indices into the scene, the text of a
 * status). Aborts when a decoder accepts what its contract excludes. */
void fuzz_decode_message(int type, const uint8_t *data, int size);

/* The key of the authenticated seeds and runs of the link harness (not a secret). */
extern const uint8_t fuzz_auth_key[32];

/* abort() with a message: a violated contract is a finding like a crash */
#define FUZZ_ASSERT(cond)                                                                          \
    do {                                                                                           \
        if (!(cond))                                                                               \
            fuzz_fail(__FILE__, __LINE__, #cond);                                                  \
    } while (0)
void fuzz_fail(const char *file, int line, const char *what);

/* The bytes of the file at `path` in a buffer of exactly their size (free it), their count in
 * *size; NULL when it cannot be read (fuzz_file.c). */
uint8_t *fuzz_read_file(const char *path, size_t *size);

#endif
