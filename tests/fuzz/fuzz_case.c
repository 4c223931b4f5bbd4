/* Harness: the case loader (common/io/case.c) on the bytes of a case file. The file is named as if
 * it lay in cases/, so the relative STL paths of the seeds resolve. A case that loads must travel
 * as a scene message and come back as the same case (what the nodes rebuild); a case that does
 * not must come with one message naming the file. */
#include <stdlib.h>
#include <string.h>
#include "case.h"
#include "fuzz.h"
#include "msg_check.h"
#include "scene_msg.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > (1u << 20))
        return 0;
    lahar_case c;
    char err[2048];
    const char *path = LAHAR_FUZZ_CASE_PATH;
    int rc = lahar_case_load_mem(path, data, size, &c, err, sizeof err);
    if (rc != 0) {
        FUZZ_ASSERT(rc == LAHAR_EXIT_BAD_INPUT);
        FUZZ_ASSERT(strncmp(err, path, strlen(path)) == 0);
        return 0;
    }
    lahar_scene_t m;
    FUZZ_ASSERT(lahar_scene_msg_from_case(&c, "/nonexistent", 1, 1, 42, &m) == 0);
    int n = lahar_scene_t_encoded_size(&m);
    uint8_t *buf = malloc((size_t)n + 1);
    FUZZ_ASSERT(buf && lahar_scene_t_encode(buf, 0, n, &m) == n);
    lahar_scene_msg_release(&m);
    lahar_scene_t back;
    FUZZ_ASSERT(lahar_msg_check(lahar_scene_t_get_type_info(), buf, n) == 0);
    FUZZ_ASSERT(lahar_scene_t_decode(buf, 0, n, &back) == n);
    lahar_case d;
    char e2[512];
    FUZZ_ASSERT(lahar_scene_msg_to_case(&back, &d, e2, sizeof e2) == 0);
    FUZZ_ASSERT(d.nbody == c.nbody && d.nblock == c.nblock && d.nmaterial == c.nmaterial && d.nprobe == c.nprobe);
    lahar_case_free(&d);
    lahar_scene_t_decode_cleanup(&back);
    free(buf);
    lahar_case_free(&c);
    return 0;
}
