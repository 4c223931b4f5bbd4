/* DEM step cost: a pile of mixed sphero-polyhedra (dem_pile.h, `layers` layers, default 4)
 * settles for `warm` seconds (default 0.3 s: the top layer has landed), then `meas` seconds
 * (default 0.05 s) of coordinator steps of 1 ms are timed. Prints one table row per body count and thread count:
 * bodies, contacts, substeps/s, microseconds per body-substep, threads, and a digest of the final
 * body states (equal digest = bitwise equal result). Never fails on time.
 *
 *   bench_dem [--hertz] [--kind mixed|spheres|boxes|rocks] [--layers n] [--warm s] [--meas s] [--threads 1,2] [n ...]  (default 500 2000 8000)
 *   bench_dem --case cases/dem_drop_3d.yaml [--warm s] [--meas s]           (a case file as is)
 *   bench_dem --lammps-data FILE [--warm-steps n] [--steps n] [--threads t] [--no-lammps]
 *             [--check-ke factor] [--check-contacts rel]
 *     a settled LAMMPS pile (atom_style sphere data file), timed against LAMMPS on the same file in
 *     the same run when built with liblammps (bench_lammps.h); the checks make it a test
 *   --restart FILE (one scene only): read the warmed-up state from FILE when it exists, else
 *   write it there after the warm-up (profiling runs then skip the warm-up).
 *
 * Wall times on a shared machine vary: run it more than once (the `bench` target runs it once). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "case.h"
#include "bench_lammps.h"
#include "dem_engine.h"
#include "dem_pile.h"
#include "dem_test_util.h"

/* The timed part, a function of its own so that a profiler can collect only it:
 * valgrind --tool=callgrind --collect-atstart=no --toggle-collect='bench_measure*' bench_dem ...
 * (the pattern also matches the clone gcc may make, bench_measure.constprop.0) */
static __attribute__((noinline)) long bench_measure(const lahar_dem_engine_ops *ops, lahar_dem_engine *e, int nmeas,
                                                    double dt, char *err, size_t errlen)
{
    long nsub = 0;
    for (int k = 0; k < nmeas; k++) {
        int n = ops->advance(e, dt, NULL, err, errlen);
        if (n < 0) return -1;
        nsub += n;
    }
    return nsub;
}

/* CPU time of the process (all threads): on a shared machine the wall time is mostly waiting. */
static double bench_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Warm the scene up once (on the largest thread count), then time `meas` seconds on each thread
 * count from the same restart: the rows of one scene start from the same state, and their digests
 * must agree (the engine is bitwise independent of the thread count). */
static int bench_scene(const lahar_case *c, double warm, double meas, const int *thr, int nthr, const char *label,
                       const char *restart)
{
    int tmax = 1;
    for (int t = 0; t < nthr; t++) tmax = thr[t] > tmax ? thr[t] : tmax;
    omp_set_num_threads(tmax);
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(c, &ops);
    char err[512];
    const double dt = 1e-3; /* one coordinator step */
    int nwarm = (int)(warm / dt + 0.5), nmeas = (int)(meas / dt + 0.5);
    FILE *saved = restart ? fopen(restart, "rb") : NULL;
    if (saved) { /* the warmed-up state of an earlier run of the same scene */
        if (ops->read_restart(e, saved)) {
            fprintf(stderr, "bench_dem: %s is not a restart of this scene\n", restart);
            fclose(saved);
            ops->destroy(e);
            return -1;
        }
        fclose(saved);
        nwarm = 0;
    }
    for (int k = 0; k < nwarm; k++)
        if (ops->advance(e, dt, NULL, err, sizeof err) < 0) {
            fprintf(stderr, "bench_dem: warm-up: %s\n", err);
            ops->destroy(e);
            return -1;
        }
    if (restart && !saved) {
        saved = fopen(restart, "wb");
        if (!saved || ops->write_restart(e, saved)) fprintf(stderr, "bench_dem: cannot write %s\n", restart);
        if (saved) fclose(saved);
    }
    FILE *f = tmpfile();
    if (!f || ops->write_restart(e, f)) {
        fprintf(stderr, "bench_dem: cannot write the restart\n");
        ops->destroy(e);
        return -1;
    }
    ops->destroy(e);
    int rc = 0;
    for (int t = 0; t < nthr && rc == 0; t++) {
        omp_set_num_threads(thr[t]);
        e = dem_test_engine(c, &ops);
        rewind(f);
        if (ops->read_restart(e, f)) {
            fprintf(stderr, "bench_dem: cannot read the restart\n");
            rc = -1;
        } else {
            double t0 = omp_get_wtime(), c0 = bench_cpu_seconds();
            long nsub = bench_measure(ops, e, nmeas, dt, err, sizeof err);
            double wall = omp_get_wtime() - t0, cpu = bench_cpu_seconds() - c0;
            if (nsub <= 0) {
                fprintf(stderr, "bench_dem: %s\n", err);
                rc = -1;
            } else {
                int nb = ops->nbody(e);
                printf("| %-14s | %6d | %8d | %6.2f | %10.1f | %15.3f | %15.3f | %7d | %016llx |\n", label, nb,
                       ops->ncontacts(e), (double)ops->ncontacts(e) / nb, nsub / wall, 1e6 * wall / ((double)nsub * nb),
                       1e6 * cpu / ((double)nsub * nb), thr[t], dem_test_digest(ops, e));
                fflush(stdout);
            }
        }
        ops->destroy(e);
    }
    fclose(f);
    return rc;
}

int main(int argc, char **argv)
{
    int kind = 0, hertz = 0, nthr = 0, thr[8], nn = 0, ns[32], layers = 4;
    double warm = 0.3, meas = 0.05;
    const char *casefile = NULL, *restart = NULL;
    bench_lammps_opts lo = {.warm = 1000, .steps = 1000, .threads = 1, .lammps = 1};
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--hertz")) hertz = 1;
        else if (!strcmp(argv[i], "--lammps-data") && i + 1 < argc) lo.file = argv[++i];
        else if (!strcmp(argv[i], "--kind") && i + 1 < argc) {
            const char *k = argv[++i];
            kind = !strcmp(k, "spheres") ? 1 : !strcmp(k, "boxes") ? 2 : !strcmp(k, "rocks") ? 3 : !strcmp(k, "mixed") ? 0 : -1;
            if (kind < 0) {
                fprintf(stderr, "bench_dem: --kind %s: expected mixed, spheres, boxes or rocks\n", k);
                return 2;
            }
        }
        else if (!strcmp(argv[i], "--warm-steps") && i + 1 < argc) lo.warm = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc) lo.steps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--no-lammps")) lo.lammps = 0;
        else if (!strcmp(argv[i], "--check-ke") && i + 1 < argc) lo.ke_tol = atof(argv[++i]);
        else if (!strcmp(argv[i], "--check-contacts") && i + 1 < argc) lo.contact_tol = atof(argv[++i]);
        else if (!strcmp(argv[i], "--warm") && i + 1 < argc) warm = atof(argv[++i]);
        else if (!strcmp(argv[i], "--layers") && i + 1 < argc) layers = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--meas") && i + 1 < argc) meas = atof(argv[++i]);
        else if (!strcmp(argv[i], "--case") && i + 1 < argc) casefile = argv[++i];
        else if (!strcmp(argv[i], "--restart") && i + 1 < argc) restart = argv[++i];
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
            for (char *s = strtok(argv[++i], ","); s && nthr < 8; s = strtok(NULL, ",")) thr[nthr++] = atoi(s);
        } else if (nn < 32 && atoi(argv[i]) > 0) ns[nn++] = atoi(argv[i]);
        else {
            fprintf(stderr, "usage: bench_dem [--hertz] [--kind mixed|spheres|boxes|rocks] [--layers n] [--warm s] [--meas s] [--threads 1,2] [--restart file] [n ...] | --case file | --lammps-data file [--warm-steps n] [--steps n] [--no-lammps] [--check-ke f] [--check-contacts r]\n");
            return 2;
        }
    }
    if (lo.file) {
        lo.threads = nthr > 0 ? thr[0] : 1;
        if (lo.steps < 1 || lo.warm < 0) {
            fprintf(stderr, "bench_dem: --steps must be >= 1 and --warm-steps >= 0\n");
            return 2;
        }
        return bench_lammps_run(&lo);
    }
    if (nthr == 0) {
        thr[nthr++] = 1;
        thr[nthr++] = 2;
    }
    if (nn == 0) {
        ns[nn++] = 500;
        ns[nn++] = 2000;
        ns[nn++] = 8000;
    }
    printf("| scene          | bodies | contacts | per body | substeps/s | us/body-substep | core-us/body-substep (CPU) | threads | state digest     |\n");
    printf("|----------------|--------|----------|--------|------------|-----------------|-----------------|---------|------------------|\n");
    int rc = 0;
    if (casefile) {
        lahar_case c;
        if (lahar_case_load(casefile, &c)) return 2;
        rc = bench_scene(&c, warm, meas, thr, nthr, "case", restart);
        lahar_case_free(&c);
        return rc ? 1 : 0;
    }
    for (int k = 0; k < nn; k++) {
        lahar_case c;
        dem_pile_case_kind(&c, ns[k], layers, hertz, 12345u, kind);
        static const char *kname[4] = {"", " spheres", " boxes", " rocks"};
        char label[32];
        snprintf(label, sizeof label, "pile %s%s", hertz ? "hertz" : "linear", kname[kind]);
        rc |= bench_scene(&c, warm, meas, thr, nthr, label, nn == 1 ? restart : NULL);
        dem_test_case_free(&c);
    }
    return rc ? 1 : 0;
}
