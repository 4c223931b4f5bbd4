/* The append-only streams (forces.h5, gauges.h5) do not grow the writer's memory over a long run.
 * HDF5's default chunk cache keeps up to 1 MiB of chunks per dataset, so every dataset of a
 * stream grew its node by up to 1 MiB although nothing is read back (gauges.h5 of 30 probes
 * written every step: +30 MB in 40,000 steps of debris_2d, docs/bench/liveness.md). Here the
 * force stream of 2 bodies and 6 trackers (9 datasets each) are written for 40,960 rows after
 * 4,096 rows of warm-up; the resident set may grow by at most 1.5 MB in each phase (with the default
 * cache it grew by about 3 MB for the forces and 18 MB for the trackers).
 * Skipped (77) under AddressSanitizer.
 *   test_output_memory OUTDIR */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "output.h"
#include "shape_build.h"

#define NTRACKER 6
#define WARM_ROWS 4096
#define ROWS 40960
#define LIMIT_KB 1536

#if defined(__SANITIZE_ADDRESS__)
#define TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TEST_ASAN 1
#endif
#endif

static long rss_kb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = -1;
    while (f && fgets(line, sizeof line, f))
        if (strncmp(line, "VmRSS:", 6) == 0)
            kb = atol(line + 6);
    if (f)
        fclose(f);
    return kb;
}

int main(int argc, char **argv)
{
#ifdef TEST_ASAN
    /* AddressSanitizer's allocator holds freed blocks in its quarantine: the resident set says
     * nothing about the writer's own memory there */
    printf("skipped: built with AddressSanitizer\n");
    return 77;
#endif
    const char *dir = argc > 1 ? argv[1] : "test_output_memory_dir";
    mkdir(dir, 0755);
    lahar_material mat = {.name = "rock", .density = 2650, .restitution = 0.5, .friction = 0.5};
    lahar_body b[2];
    memset(b, 0, sizeof b);
    snprintf(b[0].name, sizeof b[0].name, "ball");
    snprintf(b[1].name, sizeof b[1].name, "floor");
    double c0[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {1, 1};
    lahar_shape_make_sphere(&b[0].shape, 0.05);
    lahar_shape_make_plane(&b[1].shape, c0, n, size, 0.001);
    b[0].q[0] = b[1].q[0] = 1.0;
    b[0].mass = 1.0;
    b[1].motion = LAHAR_MOTION_FIXED;
    lahar_probe pr[NTRACKER];
    memset(pr, 0, sizeof pr);
    for (int k = 0; k < NTRACKER; k++) {
        snprintf(pr[k].name, sizeof pr[k].name, "tracker%d", k);
        pr[k].kind = LAHAR_PROBE_TRACKER;
        pr[k].body = -1;
        pr[k].x[0] = 0.1 * k;
    }
    lahar_case cs = {.dim = 3, .nmaterial = 1, .materials = &mat, .nbody = 2, .bodies = b, .output_forces = 1,
                     .nprobe = NTRACKER, .probes = pr};
    char err[512];
    int fail = 0;

    /* the force stream of two bodies */
    lahar_body_output *o = lahar_body_output_open(dir, &cs, err, sizeof err);
    if (!o) {
        fprintf(stderr, "FAIL forces.h5: %s\n", err);
        return 1;
    }
    long before = 0;
    for (int64_t i = 0; i < WARM_ROWS + ROWS; i++) {
        if (i == WARM_ROWS)
            before = rss_kb();
        lahar_body_report r[2];
        memset(r, 0, sizeof r);
        r[0].force[2] = -9.81 * (double)i;
        r[1].force[2] = 9.81 * (double)i;
        r[1].ncontacts = 1;
        if (lahar_body_output_forces(o, i, 1e-4 * (double)i, r) != 0) {
            fprintf(stderr, "FAIL forces.h5: row %lld failed\n", (long long)i);
            return 1;
        }
    }
    if (before < 0 || rss_kb() < 0) {
        fprintf(stderr, "FAIL cannot read VmRSS from /proc/self/status: nothing measured\n");
        return 1;
    }
    long grown = rss_kb() - before;
    lahar_body_output_close(o);
    printf("%s forces.h5: 2 bodies, %d rows after %d of warm-up: resident set grew by %ld kB (limit %d)\n",
           grown <= LIMIT_KB ? "ok  " : "FAIL", ROWS, WARM_ROWS, grown, LIMIT_KB);
    fail |= grown > LIMIT_KB;

    /* trackers: 7 values each per row */
    lahar_gauge_output *g = lahar_gauge_output_open(dir, &cs, err, sizeof err);
    if (!g) {
        fprintf(stderr, "FAIL gauges.h5: %s\n", err);
        return 1;
    }
    double v[NTRACKER * 7];
    int due[NTRACKER];
    for (int k = 0; k < NTRACKER; k++)
        due[k] = 1;
    for (int64_t i = 0; i < WARM_ROWS + ROWS; i++) {
        if (i == WARM_ROWS)
            before = rss_kb();
        for (int k = 0; k < NTRACKER * 7; k++)
            v[k] = (double)i + 0.01 * k;
        if (lahar_gauge_output_write(g, i, 1e-4 * (double)i, v, due) != 0) {
            fprintf(stderr, "FAIL gauges.h5: write of row %lld failed\n", (long long)i);
            return 1;
        }
    }
    grown = rss_kb() - before;
    lahar_gauge_output_close(g);
    printf("%s gauges.h5: %d trackers, %d rows after %d of warm-up: resident set grew by %ld kB (limit %d)\n",
           grown <= LIMIT_KB ? "ok  " : "FAIL", NTRACKER, ROWS, WARM_ROWS, grown, LIMIT_KB);
    fail |= grown > LIMIT_KB;

    lahar_shape_free(&b[0].shape);
    lahar_shape_free(&b[1].shape);
    char path[1200];
    snprintf(path, sizeof path, "%s/gauges.h5", dir); /* 19 MB and 7 MB: not kept */
    unlink(path);
    snprintf(path, sizeof path, "%s/forces.h5", dir);
    unlink(path);
    return fail;
}
