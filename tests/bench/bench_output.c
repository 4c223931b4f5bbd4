/* Cost of a particle snapshot (lahar_particle_output_snapshot: every field of a water scene, 76
 * bytes per particle) at several particle counts. Prints one row per count: snapshots written,
 * milliseconds per snapshot (median of the snapshots), the data rate, and the room the file and
 * its twin (common/io/output_snapfile.c) take on the disk while the writer is open. Never fails
 * on time.
 *
 *   bench_output [OUTDIR] [N ...]     (default OUTDIR bench_output_dir, N 2400 100000 1000000)
 *
 * The files land in the page cache: the figure is HDF5's and lahar's own cost, not the disk's.
 * Wall times on a shared machine vary: run it more than once. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include "output.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double file_mb(const char *dir, const char *name)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_size / 1e6 : 0.0;
}

/* n particles, snapshots until about 200 MB of data are written (at least 10, at most 200). */
static int bench_one(const char *dir, long n)
{
    int nsnap = (int)(200e6 / (76.0 * (double)n));
    nsnap = nsnap < 10 ? 10 : nsnap > 200 ? 200 : nsnap;
    lahar_case c;
    memset(&c, 0, sizeof c);
    c.dim = 3, c.sph_dx = 0.01, c.sph_density = 1000;
    char err[512];
    lahar_particle_output *o = lahar_particle_output_open(dir, &c, LAHAR_PFIELD_ALL, err, sizeof err);
    double *v = malloc((size_t)n * 8 * sizeof *v), *ms = malloc((size_t)nsnap * sizeof *ms);
    int32_t *phase = calloc((size_t)n, sizeof *phase);
    int64_t *id = malloc((size_t)n * sizeof *id);
    if (!o || !v || !ms || !phase || !id) {
        fprintf(stderr, "bench_output: %s\n", o ? "out of memory" : err);
        return 1;
    }
    for (long i = 0; i < 8 * n; i++)
        v[i] = 1e-3 * (double)i;
    for (long i = 0; i < n; i++)
        id[i] = i;
    lahar_particles_view p = {.n = n, .x = v, .y = v + n, .z = v + 2 * n, .vx = v + 3 * n, .vy = v + 4 * n,
                              .vz = v + 5 * n, .density = v + 6 * n, .pressure = v + 7 * n, .phase = phase, .id = id};
    double total = 0.0;
    for (int k = 0; k < nsnap; k++) {
        double t0 = now();
        if (lahar_particle_output_snapshot(o, k, 0.01 * k, &p) != 0)
            return 1;
        ms[k] = 1e3 * (now() - t0);
        total += ms[k];
    }
    double disk = file_mb(dir, "particles.h5") + file_mb(dir, ".particles.h5.twin");
    lahar_particle_output_close(o);
    qsort(ms, (size_t)nsnap, sizeof *ms, cmp_double);
    printf("| %ld | %d | %.2f | %.0f | %.1f | %.1f |\n", n, nsnap, ms[nsnap / 2], 76.0 * (double)n * nsnap / (1e3 * total),
           file_mb(dir, "particles.h5"), disk);
    free(v), free(ms), free(phase), free(id);
    return 0;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "bench_output_dir";
    mkdir(dir, 0755);
    printf("| particles | snapshots | ms per snapshot (median) | MB/s | particles.h5 MB | on disk while open, MB |\n");
    printf("|---|---|---|---|---|---|\n");
    int rc = 0;
    if (argc > 2)
        for (int i = 2; i < argc; i++)
            rc |= bench_one(dir, atol(argv[i]));
    else
        for (long n = 2400; n <= 1000000; n = n == 2400 ? 100000 : 10 * n)
            rc |= bench_one(dir, n);
    return rc;
}
